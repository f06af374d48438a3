"""Results a league can trust: each machine has its own key, the organiser admits racers'
keys, and a forged, re-signed or unsigned result never reaches anyone's leaderboard; it is
listed in quarantine with a reason naming the record and the racer.

Every league here is a separate "machine" with its own signing key (the organiser, racers
ana and bob, a forger mallory), syncing through one store: the shared folder, and for the
forgery the issue describes, DynamoDB on a real loopback server too.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from league.local_racer import save_local_racer_name
from league.opening import open_league
from league.races import record_race
from league.store import League, now_iso
from league.sync.engine import SyncSummary, store_key, sync
from league.sync.record import SyncRecord, canonical_json, make_record
from league.sync.stores import open_store
from league.trust import membership
from league.trust.keys import SigningKey
from league.trust.seals import make_seal
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.league.sync.conftest import QUICK_RETRY, StoreFactory

HAIRPIN = "hairpin-circuit"


class Machine:
    """One racer's laptop: a league database and a signing key of its own."""

    def __init__(self, root: Path, name: str, url: str) -> None:
        self.key = SigningKey.generate()
        self.league: League = open_league(root / f"{name}.db")
        self.url = url
        if name != "viewer":
            save_local_racer_name(self.league, name)  # `racer-tui racer me NAME`

    def sync(self) -> SyncSummary:
        with open_store(self.url, retry=QUICK_RETRY) as store:
            return sync(self.league, store, store_key(self.url), signing_key=self.key)

    def board(self) -> dict[str, float]:
        """Each racer's best race lap on the board, as the leaderboard shows it."""
        rows = self.league.query("SELECT racer, best_lap FROM board WHERE method = 'best_lap'")
        return {row["racer"]: row["best_lap"] for row in rows}

    def quarantine(self) -> dict[str, str]:
        return {
            row["location"]: row["reason"]
            for row in self.league.query("SELECT location, reason FROM sync_quarantine")
        }

    def race(self, racer: str, laps: list[float]) -> str:
        # Raced now with the racer's own model: a result dated before the league was
        # founded, or driven with another racer's model, is not theirs.
        track = resolve_track(HAIRPIN)
        result = race_result(racer, laps, track=track, model=f"car-{racer}", started_at=now_iso())
        return record_race(self.league, result)


@pytest.fixture
def machines(store_url: str, open_racer_store: StoreFactory, tmp_path: Path):  # type: ignore[no-untyped-def]
    """The organiser (who founded the store) and racers ana and bob, ana admitted."""
    made: dict[str, Machine] = {}
    for name in ("organiser", "ana", "bob", "mallory", "viewer"):
        made[name] = Machine(tmp_path, name, store_url)
    organiser = made["organiser"]
    membership.found_league(organiser.league, organiser.key)
    organiser.sync()
    for name in ("ana", "bob", "mallory"):
        made[name].race(name, [12.0, 11.8])
        made[name].sync()  # proposes the machine's key under its racer's name
    organiser.sync()
    membership.admit(organiser.league, organiser.key, "ana")
    membership.admit(organiser.league, organiser.key, "bob")
    organiser.sync()
    yield made
    for machine in made.values():
        machine.league.close()


def _race_file(url: str, race_id: str) -> Path:
    return Path(url.removeprefix("dir:")) / "records" / "race" / race_id[-1] / f"{race_id}.json"


def _rewrite_in_store(url: str, record: SyncRecord) -> None:
    """Overwrite what the store holds for `record`'s key, as someone with write access to
    the shared folder or the table could."""
    if url.startswith("dir:"):
        from league.sync.record import encode_envelope

        _race_file(url, record.record_id).write_bytes(encode_envelope(record))
        return
    from league.sync.aws import dynamodb_client
    from league.sync.dynamodb_table import record_item
    from league.sync.urls import DynamoDbUrl, parse_store_url

    parsed = parse_store_url(url)
    assert isinstance(parsed, DynamoDbUrl)
    client = dynamodb_client("us-east-1", parsed.endpoint, QUICK_RETRY, 1)
    client.put_item(TableName=parsed.table, Item=record_item(record, 1_900_000_000_000))


def _stored_race(machine: Machine, race_id: str) -> SyncRecord:
    from league.records import record_body

    body = record_body(machine.league, "races", race_id)
    return make_record("race", race_id, body)


def _five_second_laps(record: SyncRecord) -> dict[str, object]:
    body = json.loads(canonical_json(record.body))
    body["laps"] = [
        {**lap, "time_seconds": 5.0, "raw_seconds": 5.0, "penalty_seconds": 0.0}
        for lap in body["laps"]
    ]
    return body


def test_the_issues_forgery_reaches_nobody_and_is_listed_with_its_reason(
    machines: dict[str, Machine],
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    honest = _stored_race(ana, race_id)
    # Every lap made 5.0 s (still over the hairpin's floor, 4.5 s), the content
    # hash recomputed so the record looks whole, ana's seal left on it.
    forged_body = _five_second_laps(honest)
    forged = make_record("race", race_id, forged_body)
    assert forged.content_hash == hashlib.sha256(canonical_json(forged_body)).hexdigest()
    _rewrite_in_store(ana.url, forged.sealed(make_seal(honest, ana.key)))

    summary = viewer.sync()
    assert viewer.league.query_one("SELECT count(*) FROM races WHERE id = ?", (race_id,))[0] == 0
    assert min(viewer.board().values()) > 11.0  # nobody shows a 5.0 s lap
    (reason,) = [r for where, r in viewer.quarantine().items() if race_id in where]
    assert "signature does not match its content" in reason
    assert any(race_id in line for line in summary.quarantined)


@pytest.mark.parametrize(
    ("signer", "expected"),
    [
        # Re-signed by a key nobody admitted: held, with how the organiser would admit it.
        ("mallory", "racer ana's, but signed with key"),
        # Re-signed by another admitted racer: it claims to be ana's.
        ("bob", "claims to be racer ana's, but it is signed with racer bob's key"),
    ],
)
def test_a_result_re_signed_by_the_wrong_key_never_reaches_a_leaderboard(
    machines: dict[str, Machine], signer: str, expected: str
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    forged = make_record("race", race_id, _five_second_laps(_stored_race(ana, race_id)))
    wrong = machines[signer].key
    _rewrite_in_store(ana.url, forged.sealed(make_seal(forged, wrong)))

    viewer.sync()
    assert viewer.league.query_one("SELECT count(*) FROM races WHERE id = ?", (race_id,))[0] == 0
    (reason,) = [r for where, r in viewer.quarantine().items() if race_id in where]
    assert expected in reason
    assert min(viewer.board().values()) > 11.0


def test_a_result_made_on_a_machine_in_another_racers_name_is_refused(
    machines: dict[str, Machine],
) -> None:
    bob, viewer = machines["bob"], machines["viewer"]
    posing = bob.race("ana", [10.0, 10.1])  # bob's machine, ana's name
    bob.sync()
    viewer.sync()
    assert viewer.league.query_one("SELECT count(*) FROM races WHERE id = ?", (posing,))[0] == 0
    reason = viewer.quarantine()[f"race {posing}"]
    assert reason == "it claims to be racer ana's, but it is signed with racer bob's key"


def test_an_unadmitted_racer_waits_in_quarantine_until_the_organiser_admits_them(
    machines: dict[str, Machine],
) -> None:
    organiser, mallory, viewer = machines["organiser"], machines["mallory"], machines["viewer"]
    viewer.sync()
    assert "mallory" not in viewer.board()
    held = [r for where, r in viewer.quarantine().items() if where.startswith("race ")]
    assert held and all("`racer-tui racer admit mallory`" in reason for reason in held)
    keys = {row.racer: row.status for row in membership.key_rows(viewer.league, viewer.key)}
    assert keys["mallory"] == "proposed" and keys["ana"] == "racer"

    membership.admit(organiser.league, organiser.key, "mallory")
    assert "mallory" in organiser.board()  # released on the organiser's machine at once
    organiser.sync()
    summary = viewer.sync()  # the admission arrives: what was held is let in
    assert summary.released >= 3  # mallory's racer, track and race
    assert viewer.board()["mallory"] == pytest.approx(11.8)
    assert not [where for where in viewer.quarantine() if "mallory" in where]
    assert mallory.sync().quarantined == []


def test_only_an_organiser_runs_nights_and_admits_keys(machines: dict[str, Machine]) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    from league.seasons import new_season

    with pytest.raises(Exception, match="only the league's organiser can admit keys"):
        membership.admit(ana.league, ana.key, "mallory")
    season = new_season(ana.league, "ana's own season")
    ana.sync()
    viewer.sync()
    assert viewer.league.query("SELECT * FROM seasons") == []
    reason = viewer.quarantine()[f"season {season.id}"]
    assert reason == "it is signed by racer ana, but only an organiser makes a season"


def test_a_revoked_key_loses_every_result_and_a_retired_one_keeps_its_past(
    machines: dict[str, Machine],
) -> None:
    organiser, ana, viewer = (machines[n] for n in ("organiser", "ana", "viewer"))
    viewer.sync()
    assert set(viewer.board()) >= {"ana", "bob"}

    membership.revoke(organiser.league, organiser.key, "bob")
    membership.retire(organiser.league, organiser.key, "ana")
    assert "bob" not in organiser.board()  # withdrawn here at once
    organiser.sync()
    later = ana.race("ana", [11.0, 11.1])  # signed after the retirement
    ana.sync()
    summary = viewer.sync()
    assert "bob" not in viewer.board()
    assert any("bob" in line for line in summary.withdrawn)
    assert viewer.board()["ana"] == pytest.approx(11.8)  # the race from before stays
    assert "which the organiser retired" in viewer.quarantine()[f"race {later}"]
    assert "which the organiser revoked" in " ".join(viewer.quarantine().values())


def test_an_unsigned_record_is_quarantined_as_unsigned(
    machines: dict[str, Machine], open_racer_store: StoreFactory
) -> None:
    viewer = machines["viewer"]
    body = {
        "name": "ghost",
        "display_name": "ghost",
        "colour": "#123456",
        "created_at": "2026-11-01T00:00:00.000Z",
    }
    from sim.foundation.ids import new_id

    record = make_record("racer", new_id(), body)
    open_racer_store().push([record])  # written without a seal
    viewer.sync()
    assert "ghost" not in {row["name"] for row in viewer.league.query("SELECT name FROM racers")}
    reason = viewer.quarantine()[f"racer {record.record_id}"]
    assert reason.startswith("it is not signed, so nobody can tell who made it")


def test_a_forged_admission_counts_for_nothing(machines: dict[str, Machine]) -> None:
    mallory, viewer = machines["mallory"], machines["viewer"]
    # mallory writes an admission of her own key, naming herself as the signer.
    from league.records import store_record
    from sim.foundation.ids import new_id

    body = {
        "action": "admit",
        "public_key": mallory.key.public_hex,
        "racer": "mallory",
        "role": "organiser",
        "signed_by": mallory.key.public_hex,
        "kept": None,
        "league": new_id(),
        "created_at": now_iso(),  # made now, as its id says
    }
    act_id = new_id()
    store_record(mallory.league, "roster", act_id, body)
    mallory.sync()
    viewer.sync()
    assert "mallory" not in viewer.board()
    reason = viewer.quarantine()[f"roster {act_id}"]
    assert "only the organiser's own key changes the roster" in reason


def test_the_signing_key_is_private_and_one_per_data_directory(tmp_path: Path) -> None:
    import os
    import stat

    from league.trust.keys import KeyFileError, key_file, load_or_create_key

    first = load_or_create_key(tmp_path)
    assert load_or_create_key(tmp_path).public_hex == first.public_hex
    path = key_file(tmp_path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    os.chmod(path, 0o644)
    with pytest.raises(KeyFileError, match="can be read by other users"):
        load_or_create_key(tmp_path)
    os.chmod(path, 0o600)
    path.write_bytes(b"not a key")
    with pytest.raises(KeyFileError, match="is not an Ed25519 signing key"):
        load_or_create_key(tmp_path)


def test_a_co_host_runs_nights_but_changes_nobodys_key(machines: dict[str, Machine]) -> None:
    organiser, bob, viewer = machines["organiser"], machines["bob"], machines["viewer"]
    membership.admit(organiser.league, organiser.key, "mallory", organiser=True)
    organiser.sync()
    bob.sync()
    from league.errors import LeagueError

    with pytest.raises(LeagueError, match="only the league's organiser can admit keys"):
        membership.admit(bob.league, bob.key, "mallory")
    from league.seasons import new_season

    mallory = machines["mallory"]
    mallory.sync()
    season = new_season(mallory.league, "co-host season")
    mallory.sync()
    viewer.sync()
    assert viewer.league.query_one("SELECT id FROM seasons")[0] == season.id  # a co-host's


def test_a_retired_key_cannot_backdate_a_new_result(machines: dict[str, Machine]) -> None:
    from dataclasses import replace

    from sim.foundation.ids import new_id

    organiser, ana, viewer = machines["organiser"], machines["ana"], machines["viewer"]
    membership.retire(organiser.league, organiser.key, "ana")
    organiser.sync()
    ana.sync()
    # A "new" race whose id claims it was made a year before the retirement.
    early = race_result("ana", [4.9, 4.9], track=resolve_track(HAIRPIN))
    backdated = record_race(ana.league, replace(early, result_id=new_id(now_ms=1_760_000_000_000)))
    ana.sync()
    viewer.sync()
    assert viewer.board()["ana"] == pytest.approx(11.8)  # the race from before counts
    reason = viewer.quarantine()[f"race {backdated}"]
    assert "which the organiser retired; only what it had signed before then counts" in reason


def test_a_store_founded_by_someone_else_is_refused_when_the_organiser_is_pinned(
    store_url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> None:
    from league.sync.session import save_store

    impostor = Machine(tmp_path, "impostor", store_url)
    membership.found_league(impostor.league, impostor.key)
    impostor.race("impostor", [5.0, 5.0])
    impostor.sync()
    racer = Machine(tmp_path, "ana", store_url)
    real_organiser = SigningKey.generate()
    save_store(racer.league, store_url, organiser=real_organiser.fingerprint)
    racer.sync()
    assert racer.board() == {}
    founding = [r for where, r in racer.quarantine().items() if where.startswith("roster ")]
    assert founding and "names another organiser than the one this league was told" in founding[0]
    for machine in (impostor, racer):
        machine.league.close()


def test_a_race_disproved_by_replay_never_comes_back(machines: dict[str, Machine]) -> None:
    from dataclasses import replace

    from league.sync.local import save_cursor
    from league.trust.replay import verify_races
    from sim.race.driver import reference_driver
    from sim.race.engine import run_race
    from sim.race.rules import RaceRules
    from sim.training.drivers import DriversByHash

    organiser, viewer = machines["organiser"], machines["viewer"]
    track = resolve_track(HAIRPIN)
    honest = run_race(track, RaceRules(window_seconds=30.0), reference_driver(track), seed=5)
    lap = honest.laps[0]
    quicker = replace(lap, time_seconds=lap.time_seconds - 1.0, raw_seconds=lap.raw_seconds - 1.0)
    forged = record_race(
        organiser.league, replace(honest, racer="bob", laps=(quicker, *honest.laps[1:]))
    )
    organiser.sync()
    viewer.sync()
    (verdict,) = [v for v in verify_races(viewer.league, DriversByHash()) if v.race_id == forged]
    assert verdict.outcome == "differs"

    membership.admit(organiser.league, organiser.key, "mallory")  # the roster changes
    organiser.sync()
    viewer.sync()
    with viewer.league.transaction():
        save_cursor(viewer.league, store_key(viewer.url), "")  # pull everything again
    viewer.sync()
    assert viewer.league.query_one("SELECT count(*) FROM races WHERE id = ?", (forged,))[0] == 0
    assert "its laps differ" in viewer.quarantine()[f"race {forged}"]


def test_revoking_a_co_host_takes_their_lap_disqualifications_off_the_boards(
    machines: dict[str, Machine],
) -> None:
    from league.corrections import disqualify_lap

    organiser, ana, viewer = machines["organiser"], machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [11.0, 11.5])
    ana.sync()
    membership.admit(organiser.league, organiser.key, "mallory", organiser=True)
    organiser.sync()
    mallory = machines["mallory"]
    mallory.sync()
    disqualify_lap(mallory.league, race_id, 1, reason="made up", by="mallory")
    mallory.sync()
    viewer.sync()
    assert viewer.board()["ana"] == pytest.approx(11.5)  # lap 1 disqualified

    membership.revoke(organiser.league, organiser.key, "mallory")
    organiser.sync()
    summary = viewer.sync()
    assert viewer.board()["ana"] == pytest.approx(11.0)  # the disqualification is gone
    assert any(line.startswith("correction ") for line in summary.withdrawn)


def test_a_key_proposed_under_a_look_alike_name_is_not_admitted(
    machines: dict[str, Machine], store_url: str, tmp_path: Path
) -> None:
    from league.errors import LeagueError

    organiser = machines["organiser"]
    poser = Machine(tmp_path, "\u0430na", store_url)  # Cyrillic а, then "na"
    poser.race("\u0430na", [5.0, 5.0])
    poser.sync()
    organiser.sync()
    with pytest.raises(LeagueError, match="cannot be told apart from racer 'ana'"):
        membership.admit(organiser.league, organiser.key, "\u0430na")
    assert "\u0430na" not in organiser.board()
    poser.league.close()


def test_names_are_one_racer_only_as_the_league_compares_them(
    machines: dict[str, Machine], store_url: str, tmp_path: Path
) -> None:
    # SQLite's NOCASE folds ASCII only: "Jeß" and "Jess" are two racers, so a key
    # admitted as Jeß must not sign Jess's results (Python's casefold says they are one).
    organiser, viewer = machines["organiser"], machines["viewer"]
    jess = Machine(tmp_path, "Jess", store_url)
    jess.race("Jess", [12.0, 12.2])
    jess.sync()
    eve = Machine(tmp_path, "Jeß", store_url)
    posing = eve.race("Jess", [5.0, 5.0])
    eve.sync()
    organiser.sync()
    membership.admit(organiser.league, organiser.key, "Jess")
    with pytest.raises(Exception, match="cannot be told apart from racer 'Jess'"):
        membership.admit(organiser.league, organiser.key, "Jeß")
    membership.admit(organiser.league, organiser.key, eve.key.public_hex, racer="Jeß Ex")
    organiser.sync()
    viewer.sync()
    assert viewer.league.query_one("SELECT count(*) FROM races WHERE id = ?", (posing,))[0] == 0
    assert "claims to be racer Jess's" in viewer.quarantine()[f"race {posing}"]
    for machine in (jess, eve):
        machine.league.close()


def test_an_admission_in_one_league_means_nothing_in_another(
    machines: dict[str, Machine], tmp_path: Path
) -> None:
    from league.sync.outgoing import unsent_batches
    from league.trust.seals import make_seal

    organiser, mallory, viewer = machines["organiser"], machines["mallory"], machines["viewer"]
    # The same organiser key founds a second league (next season) and admits mallory there.
    with open_league(tmp_path / "season-2.db") as other:
        membership.found_league(other, organiser.key)
        with other.transaction():
            from league.records import store_record
            from sim.foundation.ids import new_id

            act = {
                "action": "propose",
                "public_key": mallory.key.public_hex,
                "racer": "mallory",
                "role": "racer",
                "signed_by": mallory.key.public_hex,
                "kept": None,
                "league": None,
                "created_at": now_iso(),  # made now, as its id says
            }
            store_record(other, "roster", new_id(), act)
        admitted = membership.admit(other, organiser.key, "mallory")
        assert admitted.status == "racer"
        copied = [
            record
            for batch in unsent_batches(other, "nowhere")
            for record in batch.records
            if record.kind == "roster" and record.body["action"] == "admit"
        ]
    # Someone copies that admission, genuinely signed by the organiser, into this store.
    (admission,) = copied
    sealed = admission.sealed(make_seal(admission, organiser.key))
    with open_store(viewer.url, retry=QUICK_RETRY) as store:
        assert store.push([sealed]).pushed
    viewer.sync()
    assert "mallory" not in viewer.board()
    keys = {row.racer: row.status for row in membership.key_rows(viewer.league, viewer.key)}
    assert keys["mallory"] == "proposed"


def test_an_admitted_racer_cannot_show_as_someone_else(
    machines: dict[str, Machine], store_url: str, tmp_path: Path
) -> None:
    from league.records import store_record
    from sim.foundation.ids import new_id

    organiser, viewer = machines["organiser"], machines["viewer"]
    carl = Machine(tmp_path, "carl", store_url)
    body = {
        "name": "carl",
        "display_name": "ana",
        "colour": "#112233",
        "created_at": now_iso(),  # made now, as its id says
    }
    posing = new_id()
    store_record(carl.league, "racers", posing, body)
    carl.sync()
    organiser.sync()
    membership.admit(organiser.league, organiser.key, "carl")
    organiser.sync()
    viewer.sync()
    reason = viewer.quarantine()[f"racer {posing}"]
    assert (
        reason
        == "it is signed by racer carl but shows them as ana; only the organiser renames racers"
    )
    assert viewer.league.query_one("SELECT count(*) FROM racers WHERE id = ?", (posing,))[0] == 0
    carl.league.close()


def test_a_pin_that_contradicts_the_leagues_organiser_is_refused(
    machines: dict[str, Machine],
) -> None:
    from league.sync.errors import StoreUrlError
    from league.sync.session import save_store

    viewer = machines["viewer"]
    viewer.sync()
    with pytest.raises(StoreUrlError, match="this league's organiser key is"):
        save_store(viewer.league, viewer.url, organiser=SigningKey.generate().fingerprint)
    with pytest.raises(StoreUrlError, match="give all 16 hex digits"):
        save_store(viewer.league, viewer.url, organiser="2628 95d5")
    save_store(viewer.league, viewer.url, organiser=machines["organiser"].key.fingerprint)

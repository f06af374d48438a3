"""Dates and ids that agree, and a race belongs to the racer who drove it: the attacks of
issue 41, made with racer-tui's own signing functions by an admitted racer (bob) against
the organiser, ana and a fresh machine sharing one store (the folder, and DynamoDB on a
loopback server). No forged lap, date or borrowed race reaches any board.
"""

from __future__ import annotations

from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest

from league.races import record_race
from league.records import record_body
from league.store import now_iso
from league.sync.dates import DATE_TOLERANCE_MS, check_dates
from league.sync.errors import RecordInvalidError
from league.sync.kinds import MODEL_KIND
from league.sync.record import SyncRecord, make_record
from league.sync.stores import open_store
from league.trust.seals import make_seal
from sim.foundation.ids import new_id
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.league.sync.conftest import QUICK_RETRY
from tests.league.sync.test_signed_results import (  # the league of machines these tests share
    HAIRPIN,
    Machine,
    machines,  # noqa: F401 (a fixture)
)

MADE_UP = "f" * 64


def push_signed(machine: Machine, *records: SyncRecord) -> None:
    """What a 30-line script does: sign records with the machine's own key and write them."""
    with open_store(machine.url, retry=QUICK_RETRY) as store:
        store.push([record.sealed(make_seal(record, machine.key)) for record in records])


def iso(ms: int) -> str:
    return datetime.fromtimestamp(ms / 1000, UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def model_record(racer: str, model_hash: str, when_ms: int) -> SyncRecord:
    body = {
        "racer": racer,
        "model_name": "car",
        "model_hash": model_hash,
        "registered_at": iso(when_ms),
    }
    return make_record(MODEL_KIND, new_id(now_ms=when_ms), body)


def race_as(machine: Machine, race_id: str, **changes: Any) -> SyncRecord:
    """A copy of `machine`'s stored race with `changes`, under a new id unless given."""
    body = {**record_body(machine.league, "races", race_id), **changes}
    record_id = body.pop("id", None) or new_id()
    return make_record("race", record_id, body)


def pending_reasons(machine: Machine) -> dict[str, str]:
    return {
        f"{row['kind']} {row['record_id']}": row["waiting_for"]
        for row in machine.league.query("SELECT kind, record_id, waiting_for FROM sync_pending")
    }


def test_a_race_with_a_made_up_model_waits_and_then_is_refused(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    organiser, bob, viewer = machines["organiser"], machines["bob"], machines["viewer"]
    honest = bob.race("bob", [12.0, 11.9])
    bob.sync()
    # bob signs a race of his own, every lap 4.9 s, with a model hash nobody registered,
    # started nine minutes ago (the league was founded moments before).
    now = int(datetime.now(UTC).timestamp() * 1000)
    forged = race_as_laps(
        race_as(bob, honest, model_hash=MADE_UP, started_at=iso(now - 9 * 60_000)), 4.9
    )
    push_signed(bob, forged)
    for machine in (organiser, viewer):
        machine.sync()
        assert machine.board()["bob"] == pytest.approx(11.8)  # his honest races only
        assert pending_reasons(machine)[f"race {forged.record_id}"].startswith(
            "racer bob's model record for model ffffffffffff"
        )
    # Registering the made-up model afterwards does not make the race his.
    push_signed(bob, model_record("bob", MADE_UP, now + 5 * 60_000))
    for machine in (organiser, viewer):
        summary = machine.sync()
        assert machine.board()["bob"] == pytest.approx(11.8)
        assert f"race {forged.record_id}" not in pending_reasons(machine)
        reason = machine.quarantine()[f"race {forged.record_id}"]
        assert "registered its model ffffffffffff only after this result" in reason
        assert any(forged.record_id in line for line in summary.quarantined)  # and said so
        assert summary.waiting == 0


def test_a_race_whose_model_record_comes_later_waits_for_it_and_then_counts(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    organiser, bob = machines["organiser"], machines["bob"]
    honest = bob.race("bob", [12.0, 11.9])
    now = int(datetime.now(UTC).timestamp() * 1000)
    # Pushed before its model record (a push cut short between the two, say).
    race = race_as_laps(race_as(bob, honest, model_hash="hash-new-car", started_at=iso(now)), 11.1)
    push_signed(bob, race)
    organiser.sync()
    assert organiser.board()["bob"] == pytest.approx(11.8)
    assert f"race {race.record_id}" in pending_reasons(organiser)
    push_signed(bob, model_record("bob", "hash-new-car", now - 1000))
    summary = organiser.sync()
    assert organiser.board()["bob"] == pytest.approx(11.1)
    assert pending_reasons(organiser) == {} and summary.waiting == 0


def race_as_laps(record: SyncRecord, seconds: float) -> SyncRecord:
    laps = [
        {**lap, "time_seconds": seconds, "raw_seconds": seconds, "penalty_seconds": 0.0}
        for lap in record.body["laps"]
    ]
    return make_record("race", record.record_id, {**record.body, "laps": laps})


def test_a_copied_race_is_refused_as_a_copy_whatever_date_it_claims(
    machines: dict[str, Machine],  # noqa: F811
    tmp_path: Any,
    store_url: str,
) -> None:
    organiser, ana, bob = machines["organiser"], machines["ana"], machines["bob"]
    original = ana.race("ana", [11.5, 11.4])
    ana.sync()
    bob.sync()
    model_hash = str(record_body(ana.league, "races", original)["model_hash"])
    # The copy: ana's race as bob's, started 1970-01-01, its id from time 0.
    epoch = race_as(ana, original, racer="bob", started_at="1970-01-01T00:00:00.000Z")
    epoch = make_record("race", new_id(now_ms=0), dict(epoch.body))
    # The careful copy: dated just after the league's founding, with bob's own model record
    # for ana's model dated as early; and a plain copy dated now.
    founded = _founded_ms(organiser) + 1000
    early = race_as(ana, original, racer="bob", started_at=iso(founded))
    early = make_record("race", new_id(now_ms=founded + 1000), dict(early.body))
    plain = race_as(ana, original, racer="bob", started_at=now_iso())
    push_signed(bob, model_record("bob", model_hash, founded), epoch, early, plain)
    fresh = Machine(tmp_path, "fresh", store_url)
    for machine in (organiser, ana, fresh):
        machine.sync()
        assert machine.board()["ana"] == pytest.approx(11.4)
        assert "bob" not in machine.board() or machine.board()["bob"] > 11.4
        reasons = machine.quarantine()
        assert "its id claims it was made on 1970-01-01" in reasons[f"race {epoch.record_id}"]
        # Refused as a copy of ana's race, or (where the copy arrives first: a machine
        # pulling afresh sees it in id order) of the model the organiser says is ana's.
        for copy in (early, plain):
            assert any(
                words in reasons[f"race {copy.record_id}"]
                for words in (
                    f"it copies racer ana's race {original}",
                    "racer ana registered first",
                )
            )
    fresh.league.close()


def test_a_model_another_racer_registered_first_is_theirs(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    organiser, ana, bob, viewer = (machines[n] for n in ("organiser", "ana", "bob", "viewer"))
    original = ana.race("ana", [11.5, 11.4])
    ana.sync()
    model_hash = str(record_body(ana.league, "races", original)["model_hash"])
    now = int(datetime.now(UTC).timestamp() * 1000)
    # bob races ana's model himself (another seed, other laps) and registers it as his.
    borrowed = race_as(ana, original, racer="bob", seed=99, started_at=iso(now))
    borrowed = race_as_laps(borrowed, 11.0)
    push_signed(bob, model_record("bob", model_hash, now - 1000), borrowed)
    for machine in (organiser, viewer):
        machine.sync()
        assert "bob" not in machine.board() or machine.board()["bob"] > 11.0
        reason = machine.quarantine()[f"race {borrowed.record_id}"]
        assert f"it names model {model_hash[:12]}, which racer ana registered first" in reason


def test_the_organisers_word_on_a_model_goes_out_in_the_sync_that_first_sees_it(
    machines: dict[str, Machine],  # noqa: F811
    tmp_path: Any,
    store_url: str,
) -> None:
    organiser, ana, bob = machines["organiser"], machines["ana"], machines["bob"]
    # ana's new model, first raced now: her claim on it is dated now.
    result = race_result("ana", [11.5, 11.4], track=resolve_track(HAIRPIN), model="new-car")
    original = record_race(ana.league, replace(result, started_at=now_iso()))
    ana.sync()
    organiser.sync()  # sees ana's claim on her model: its word on it goes out now
    model_hash = str(record_body(ana.league, "races", original)["model_hash"])
    # Later, bob claims ana's model with a record dated just after the founding, and races
    # it. A machine that pulls everything at once sees his claim first in id order.
    founded = _founded_ms(organiser) + 1000
    borrowed = race_as(ana, original, racer="bob", seed=99, started_at=now_iso())
    push_signed(bob, model_record("bob", model_hash, founded), race_as_laps(borrowed, 11.0))
    fresh = Machine(tmp_path, "fresh", store_url)
    fresh.sync()  # before the organiser's next sync
    assert "bob" not in fresh.board() or fresh.board()["bob"] > 11.0
    reason = fresh.quarantine()[f"race {borrowed.record_id}"]
    assert "racer ana registered first" in reason
    fresh.league.close()


def test_a_racers_results_from_before_the_league_do_not_count_in_it(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    organiser, ana, viewer = machines["organiser"], machines["ana"], machines["viewer"]
    original = ana.race("ana", [11.5, 11.4])
    ana.sync()
    before = _founded_ms(organiser) - 2 * DATE_TOLERANCE_MS
    old = race_as(ana, original, started_at=iso(before))
    old = race_as_laps(make_record("race", new_id(now_ms=before + 1000), dict(old.body)), 11.0)
    push_signed(ana, old)
    viewer.sync()
    assert viewer.board()["ana"] == pytest.approx(11.4)
    assert "before this league was founded" in viewer.quarantine()[f"race {old.record_id}"]


def test_a_tie_goes_to_the_result_seen_first_not_to_an_early_date(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    organiser, ana, bob = machines["organiser"], machines["ana"], machines["bob"]
    bob.race("bob", [11.5, 11.2])
    bob.sync()
    organiser.sync()
    # ana's own race, the same best lap, written as if raced before the league began, as
    # far as the tolerance for clocks allows (ties go to the earlier result, and "ana"
    # sorts before "bob" too).
    honest = ana.race("ana", [11.6, 11.3])
    founded = _founded_ms(organiser) - DATE_TOLERANCE_MS + 100
    tied = race_as(ana, honest, started_at=iso(founded), model_hash="hash-early")
    tied = make_record("race", new_id(now_ms=founded + 1), dict(race_as_laps(tied, 11.2).body))
    ana.sync()
    push_signed(ana, model_record("ana", "hash-early", founded - 50), tied)
    organiser.sync()
    order = [
        row["racer"]
        for row in organiser.league.query(
            "SELECT racer FROM board WHERE method = 'best_lap' ORDER BY unscored, score, "
            "scoring_offtracks, valid_laps DESC, recorded_at, racer"
        )
    ]
    assert organiser.board()["ana"] == organiser.board()["bob"] == pytest.approx(11.2)
    assert order.index("bob") < order.index("ana")


def _founded_ms(organiser: Machine) -> int:
    from league.sync.dates import founded_ms
    from league.trust.roster import Roster

    founded = founded_ms(Roster.load(organiser.league))
    assert founded is not None
    return founded


# --- dates of each kind, record by record ----------------------------------------------------


def _racer(created_at: str, made_ms: int) -> SyncRecord:
    body = {"name": "ana", "display_name": "ana", "colour": "#123456", "created_at": created_at}
    return make_record("racer", new_id(now_ms=made_ms), body)


def test_a_records_date_must_agree_with_its_id() -> None:
    now = int(datetime.now(UTC).timestamp() * 1000)
    check_dates(_racer(iso(now), now))
    check_dates(_racer(iso(now - DATE_TOLERANCE_MS + 1000), now))
    with pytest.raises(RecordInvalidError, match=r"its created_at .* disagree"):
        check_dates(_racer(iso(now - 2 * DATE_TOLERANCE_MS), now))
    with pytest.raises(RecordInvalidError, match="cannot be true"):
        check_dates(_racer(iso(now + 2 * DATE_TOLERANCE_MS), now + 2 * DATE_TOLERANCE_MS))
    model = model_record("ana", MADE_UP, now)
    check_dates(model)
    moved = make_record(MODEL_KIND, model.record_id, {**model.body, "registered_at": iso(0)})
    with pytest.raises(RecordInvalidError, match=r"its registered_at .* disagree"):
        check_dates(moved)


# --- on this machine ---------------------------------------------------------------------


def test_submitting_a_model_another_racer_registered_is_refused_here_too(
    machines: dict[str, Machine],  # noqa: F811
    tmp_path: Path,
) -> None:
    from league.assembler import assemble
    from league.errors import LeagueError
    from league.submissions import submit
    from tests.league.helpers import model_folder

    ana, bob = machines["ana"], machines["bob"]
    folder = model_folder(tmp_path / "ana-car", laps=(12.4, 12.1, 12.9))
    submit(ana.league, assemble(str(folder), "ana"))
    ana.sync()
    bob.sync()  # ana's model record is here now
    borrowed = model_folder(tmp_path / "borrowed", laps=(12.0, 11.9, 12.2))  # the same car
    with pytest.raises(LeagueError, match="is racer ana's \\(they registered it first\\)"):
        submit(bob.league, assemble(str(borrowed), "bob"))
    assert bob.league.query_one("SELECT count(*) FROM submissions WHERE racer = 'bob'")[0] == 0


def test_a_copied_submission_is_refused_as_a_copy(
    machines: dict[str, Machine],  # noqa: F811
    tmp_path: Path,
) -> None:
    from league.assembler import assemble
    from league.submissions import submit
    from tests.league.helpers import model_folder

    organiser, ana, bob, viewer = (machines[n] for n in ("organiser", "ana", "bob", "viewer"))
    folder = model_folder(tmp_path / "ana-car", laps=(11.4, 11.6, 11.9))
    original = submit(ana.league, assemble(str(folder), "ana")).submission_id
    ana.sync()
    body = {**record_body(ana.league, "submissions", original), "racer": "bob"}
    copy = make_record("submission", new_id(), {**body, "submitted_at": now_iso()})
    push_signed(bob, copy)
    for machine in (organiser, viewer):
        machine.sync()
        stored = machine.league.query(
            "SELECT racer FROM submissions WHERE id = ?", (copy.record_id,)
        )
        assert list(stored) == []
        reason = machine.quarantine()[f"submission {copy.record_id}"]
        assert f"it copies racer ana's submission {original}" in reason


def test_a_key_proposed_before_the_league_was_founded_can_still_be_admitted(
    machines: dict[str, Machine],  # noqa: F811
    store_url: str,
    tmp_path: Path,
) -> None:
    from league.records import store_record
    from league.trust import membership

    organiser = machines["organiser"]
    dee = Machine(tmp_path, "dee", store_url)
    # dee's laptop proposed its key when it was in another league, before this one began.
    before = _founded_ms(organiser) - 2 * DATE_TOLERANCE_MS
    act = {
        "action": "propose",
        "public_key": dee.key.public_hex,
        "racer": "dee",
        "role": "racer",
        "signed_by": dee.key.public_hex,
        "kept": None,
        "league": None,
        "created_at": iso(before),
    }
    store_record(dee.league, "roster", new_id(now_ms=before), act)
    dee.sync()
    organiser.sync()
    keys = {row.racer: row.status for row in membership.key_rows(organiser.league, organiser.key)}
    assert keys["dee"] == "proposed"
    membership.admit(organiser.league, organiser.key, "dee")
    dee.league.close()


def test_a_new_racers_old_results_stay_out_and_their_new_ones_count(
    machines: dict[str, Machine],  # noqa: F811
    store_url: str,
    tmp_path: Path,
) -> None:
    from dataclasses import replace

    from league.races import record_race
    from league.trust import membership
    from sim.tracks.catalog import resolve_track
    from tests.league.helpers import race_result
    from tests.league.sync.test_signed_results import HAIRPIN

    organiser, viewer = machines["organiser"], machines["viewer"]
    dee = Machine(tmp_path, "dee", store_url)
    # dee raced her car at home before the league began, and again since.
    before = _founded_ms(organiser) - 2 * DATE_TOLERANCE_MS
    track = resolve_track(HAIRPIN)
    old = race_result("dee", [10.0, 10.1], track=track, model="car-dee", started_at=iso(before))
    old_id = record_race(dee.league, replace(old, result_id=new_id(now_ms=before + 60_000)))
    dee.race("dee", [11.0, 10.9])
    dee.sync()  # her first: her model is registered as of her first race with it
    organiser.sync()
    membership.admit(organiser.league, organiser.key, "dee")
    organiser.sync()
    viewer.sync()
    assert viewer.board()["dee"] == pytest.approx(10.9)
    assert "before this league was founded" in viewer.quarantine()[f"race {old_id}"]
    assert pending_reasons(viewer) == {}
    dee.league.close()

"""Forged deletions do not erase honest results: a racer's record that someone deleted or
re-wrote in the store (re-hashed so that it looks whole) is kept by every machine that
had it, and written back by its maker's next sync, so that a machine pulling afresh finds
the honest result; with no genuine copy anywhere, the forgery is quarantined with its
reason, never silently nothing. On the shared folder and on DynamoDB (loopback server).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from league.sync import restore
from league.sync.aws import dynamodb_client
from league.sync.dynamodb_table import record_item
from league.sync.engine import store_key
from league.sync.protocol import SPARE_SLOTS
from league.sync.record import SyncRecord, encode_envelope, make_record
from league.sync.urls import DynamoDbUrl, parse_store_url
from league.trust.seals import make_seal
from tests.league.sync.conftest import QUICK_RETRY
from tests.league.sync.test_signed_results import (  # the league of machines these tests share
    Machine,
    machines,  # noqa: F401 (a fixture)
)

FORGED_LAP = 3.5  # under the floor: the forgeries here are refused on their laps or seal


def honest_race(machine: Machine, race_id: str) -> SyncRecord:
    from league.records import record_body

    return make_record("race", race_id, record_body(machine.league, "races", race_id))


def forgery_of(honest: SyncRecord, machine: Machine) -> SyncRecord:
    """Every lap made FORGED_LAP seconds, the hash recomputed, the maker's seal left on."""
    body = dict(honest.body)
    body["laps"] = [
        {**lap, "time_seconds": FORGED_LAP, "raw_seconds": FORGED_LAP, "penalty_seconds": 0.0}
        for lap in honest.body["laps"]
    ]
    return make_record("race", honest.record_id, body).sealed(make_seal(honest, machine.key))


def _table(url: str) -> tuple[object, str]:
    parsed = parse_store_url(url)
    assert isinstance(parsed, DynamoDbUrl)
    return dynamodb_client("us-east-1", parsed.endpoint, QUICK_RETRY, 1), parsed.table


def _file(url: str, record_id: str, spare: int = 0) -> Path:
    name = f"{record_id}.spare{spare}.json" if spare else f"{record_id}.json"
    return Path(url.removeprefix("dir:")) / "records" / "race" / record_id[-1] / name


def overwrite(url: str, record: SyncRecord, spare: int = 0) -> None:
    """Write `record` over what the store holds under its key (or spare `spare`), as anyone
    with write access to the folder or the table can."""
    if url.startswith("dir:"):
        path = _file(url, record.record_id, spare)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(encode_envelope(record))
        return
    client, table = _table(url)
    item = record_item(record, 1_900_000_000_000 + spare)
    if spare:
        item["pk"] = {"S": f"race#{record.record_id}#spare{spare}"}
        item["pushed_key"] = {"S": f"{item['pushed_key']['S']}#spare{spare}"}
    client.put_item(TableName=table, Item=item)  # type: ignore[attr-defined]


def delete(url: str, record_id: str, kind: str = "race") -> None:
    if url.startswith("dir:"):
        path = _file(url, record_id)
        (path.parent.parent.parent / kind / path.parent.name / path.name).unlink()
        return
    client, table = _table(url)
    client.delete_item(TableName=table, Key={"pk": {"S": f"{kind}#{record_id}"}})  # type: ignore[attr-defined]


def laps_of(machine: Machine, race_id: str) -> list[float]:
    rows = machine.league.query(
        "SELECT time_seconds FROM race_laps WHERE race_id = ? ORDER BY number", (race_id,)
    )
    return [row[0] for row in rows]


def test_the_honest_result_reaches_a_fresh_machine_once_its_racer_syncs_again(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    honest = honest_race(ana, race_id)
    overwrite(ana.url, forgery_of(honest, ana))

    # No genuine copy in the store yet: the fresh machine shows the forgery as quarantined.
    before = viewer.sync()
    assert laps_of(viewer, race_id) == []
    assert "signature does not match its content" in viewer.quarantine()[f"race {race_id}"]
    assert any(race_id in line for line in before.quarantined)

    restored = ana.sync()
    assert any(race_id in note and "wrote it back" in note for note in restored.notes), (
        restored.notes
    )

    viewer.sync()
    assert laps_of(viewer, race_id) == [12.5, 12.4]
    assert FORGED_LAP not in viewer.board().values()
    # Writing it back happens once: the spare copy stays genuine.
    assert not any(race_id in note for note in ana.sync().notes)


def test_a_forgery_signed_with_another_racers_key_is_written_back_too(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    # Signed by bob, whose key is admitted: the seal checks out, and the roster holds it
    # back as not ana's. ana's own sync pulls it (DynamoDB gives the re-written item again)
    # and must still know that what she pushed is gone from the store.
    ana, bob, viewer = machines["ana"], machines["bob"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    honest = honest_race(ana, race_id)
    laps = [{**lap, "time_seconds": 12.0, "raw_seconds": 12.0} for lap in honest.body["laps"]]
    body = {**honest.body, "laps": laps}
    forged = make_record("race", race_id, body)  # possible laps: only the seal tells
    overwrite(ana.url, forged.sealed(make_seal(forged, bob.key)))

    restored = ana.sync()
    assert any(race_id in note and "wrote it back" in note for note in restored.notes), (
        restored.notes
    )
    viewer.sync()
    assert laps_of(viewer, race_id) == [12.5, 12.4]
    assert "signed with racer bob's key" in viewer.quarantine()[f"race {race_id}"]


def test_a_machine_that_had_the_record_keeps_it_when_the_store_copy_is_forged(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    ana, bob = machines["ana"], machines["bob"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    bob.sync()
    assert laps_of(bob, race_id) == [12.5, 12.4]

    overwrite(ana.url, forgery_of(honest_race(ana, race_id), ana))
    bob.sync()

    assert laps_of(bob, race_id) == [12.5, 12.4]
    assert FORGED_LAP not in bob.board().values()


def test_a_deleted_record_is_written_back_under_its_own_name(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    delete(ana.url, race_id)

    notes = ana.sync().notes

    assert any(race_id in note and "wrote it back" in note for note in notes)
    if ana.url.startswith("dir:"):
        assert _file(ana.url, race_id).exists()
    viewer.sync()
    assert laps_of(viewer, race_id) == [12.5, 12.4]


def test_a_forger_who_fills_every_spare_place_is_named_to_the_maker(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    forged = forgery_of(honest_race(ana, race_id), ana)
    for spare in range(SPARE_SLOTS + 1):
        overwrite(ana.url, forged, spare)

    notes = ana.sync().notes

    (note,) = [note for note in notes if race_id in note]
    assert "every spare place for it is taken" in note
    viewer.sync()
    assert laps_of(viewer, race_id) == []
    assert "signature does not match" in viewer.quarantine()[f"race {race_id}"]


def test_a_host_with_many_records_checks_older_ones_in_turn(
    machines: dict[str, Machine],  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    races = [ana.race("ana", [12.0 + index / 10, 12.5]) for index in range(6)]
    ana.sync()
    monkeypatch.setattr(restore, "CHECKS_PER_SYNC", 4)  # the newest 2, and 2 older in turn
    oldest = races[0]
    overwrite(ana.url, forgery_of(honest_race(ana, oldest), ana))

    syncs = 0
    while not laps_of(viewer, oldest) and syncs < 5:
        ana.sync()
        viewer.sync()
        syncs += 1

    own = len(restore._own_records(ana.league, store_key(ana.url), ana.key.public_hex))
    assert own > 4
    assert laps_of(viewer, oldest) == [12.0, 12.5]
    # The 2 newest every sync, the older ones 2 at a time: each within this many syncs.
    assert syncs <= -(-(own - 2) // 2)


def test_a_deleted_model_record_is_written_back_so_its_races_do_not_wait(
    machines: dict[str, Machine],  # noqa: F811
) -> None:
    ana, viewer = machines["ana"], machines["viewer"]
    race_id = ana.race("ana", [12.5, 12.4])
    ana.sync()
    models = [
        row[0]
        for row in ana.league.query(
            "SELECT m.record_id FROM sync_models m JOIN sync_seals s ON s.kind = 'model' "
            "AND s.record_id = m.record_id WHERE s.signer = ?",
            (ana.key.public_hex,),
        )
    ]
    assert models  # ana's sync registered the model she raced
    for model_id in models:
        delete(ana.url, model_id, "model")

    notes = ana.sync().notes

    assert all(any(model_id in note for note in notes) for model_id in models)
    viewer.sync()
    assert laps_of(viewer, race_id) == [12.5, 12.4]

"""Every reset DeepRacer counts in a lap is kept: a submission's immobilized and reversed
counts beside its off-tracks and crashes, a race's crashes and reversals. DeepRacer on
AWS's rankings add them up (simapp's reset_count); a lap without them keeps the record,
and so the content hash, it had before they were counted."""

from __future__ import annotations

import json
import tarfile
from dataclasses import replace
from pathlib import Path

import pytest

from league.droa_rankings import droa_laps
from league.races import race_result as stored_race
from league.races import record_race
from league.records import record_body
from league.store import League
from league.submissions import submit_model
from league.sync.errors import RecordInvalidError
from league.sync.record import SyncRecord
from league.sync.validate import check_record
from sim.foundation.ids import content_hash
from sim.race.result import LapRecord
from tests.league.helpers import race_result
from tests.sim.garage.droa_archives import virtual_model_archive

LAP_KEYS_BEFORE = {"number", "time_seconds", "raw_seconds", "penalty_seconds", "offtracks"}
LAP_KEYS_BEFORE |= {"valid", "started_at"}


def _stored_hash(league: League, table: str, record_id: str) -> str:
    row = league.query_one(f"SELECT content_hash FROM {table} WHERE id = ?", (record_id,))
    assert row is not None
    return str(row[0])


def test_a_submission_keeps_the_resets_droa_adds_up(
    league: League, deepracer_dir: Path, tmp_path: Path
) -> None:
    folder = tmp_path / "droa"
    folder.mkdir()
    with tarfile.open(virtual_model_archive(deepracer_dir, tmp_path)) as tar:
        tar.extractall(folder, filter="data")
    [metrics_file] = (folder / "metrics" / "submission").glob("*.json")
    metrics = json.loads(metrics_file.read_text())
    first = metrics["metrics"][0]
    first.update(immobilized_count=1, reversed_count=2)
    first["reset_count"] = sum(
        first[key]
        for key in ("crash_count", "immobilized_count", "off_track_count", "reversed_count")
    )
    metrics_file.write_text(json.dumps(metrics))

    submission, submitted = submit_model(league, str(folder), "ana")

    droa = droa_laps(league, submitted.submission_id, "submission")
    assert [lap.resets for lap in droa] == [t["reset_count"] for t in metrics["metrics"]]
    body = record_body(league, "submissions", submitted.submission_id)
    assert (body["laps"][0]["immobilized"], body["laps"][0]["reversals"]) == (1, 2)
    # The other laps had none: their records are as they always were.
    assert all("immobilized" not in lap and "reversals" not in lap for lap in body["laps"][1:])
    assert content_hash(body) == _stored_hash(league, "submissions", submitted.submission_id)
    check_record(SyncRecord("submission", submitted.submission_id, content_hash(body), body))
    # Sent again, it is the same submission: its fingerprint is what it was before.
    assert submit_model(league, str(folder), "ana")[1].duplicate
    assert submission.laps[0].resets == first["reset_count"]


def test_a_race_keeps_its_crashes_and_reversals(league: League) -> None:
    result = race_result("bob", [10.0, 10.5, 11.0], offtracks=[1, 0, 0])
    rules = result.rules
    first, second, third = result.laps
    # Lap 1: an off-track, a crash and a reversal, each held for its penalty inside the lap.
    held = rules.penalty_seconds * 2 + rules.collision_penalty_seconds
    first = replace(
        first, crashes=1, reversals=1, penalty_seconds=held, time_seconds=first.raw_seconds + held
    )
    second = replace(second, started_at=first.started_at + first.time_seconds)
    third = replace(third, started_at=second.started_at + second.time_seconds)
    race_id = record_race(league, replace(result, laps=(first, second, third)))

    body = record_body(league, "races", race_id)
    assert (body["laps"][0]["crashes"], body["laps"][0]["reversals"]) == (1, 1)
    assert all(set(lap) == LAP_KEYS_BEFORE for lap in body["laps"][1:])
    assert content_hash(body) == _stored_hash(league, "races", race_id)
    check_record(SyncRecord("race", race_id, content_hash(body), body))
    assert [lap.resets for lap in stored_race(league, race_id).laps] == [3, 0, 0]
    assert [(lap.crashes, lap.resets) for lap in droa_laps(league, race_id, "race")] == [
        (1, 3),
        (0, 0),
        (0, 0),
    ]


@pytest.mark.parametrize("value", [None, 0])
def test_a_pulled_lap_gives_its_counts_one_way_only(league: League, value: int | None) -> None:
    race_id = record_race(league, race_result("cy", [10.0, 10.5]))
    body = record_body(league, "races", race_id)
    body["laps"][0]["reversals"] = value  # a writer leaves it out when there are none
    with pytest.raises(RecordInvalidError, match="reversals"):
        check_record(SyncRecord("race", race_id, content_hash(body), body))


def test_an_old_lap_without_counts_still_reads(league: League) -> None:
    lap = LapRecord.from_json(
        {key: 1 if key != "valid" else True for key in LAP_KEYS_BEFORE}
        | {"time_seconds": 2, "penalty_seconds": 1},
        "lap",
    )
    assert (lap.crashes, lap.reversals, lap.resets) == (0, 0, 1)

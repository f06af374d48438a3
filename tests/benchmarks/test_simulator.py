"""The benchmark script keeps working (figures are printed, never judged here)."""

from __future__ import annotations

import json

import pytest

from benchmarks.sim.simulator import main


def test_bench_json_reports_every_sensor_and_builtin_track(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["--json", "--seconds", "0.05", "--cars", "2"]) == 0
    report = json.loads(capsys.readouterr().out)
    rows = [(row["sensor"], row["race"]) for row in report["sensors"]]
    assert rows == [
        (sensor, race)
        for sensor in ("vector", "lidar", "camera 160x120")
        for race in ("time trial", "3 boxes", "3 bots")
    ]
    assert all(row["steps_per_s"] > 0 for row in report["sensors"])
    laps = {row["track"]: row for row in report["reference_laps"]}
    assert {"beginner-oval", "hairpin-circuit", "bowtie-chicane", "speedway", "grand-prix"} <= set(
        laps
    )
    assert all(row["status"] == "Lap complete" for row in laps.values())

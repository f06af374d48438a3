"""The race benchmark script keeps working (figures are printed, never judged here)."""

from __future__ import annotations

import json

import pytest

from benchmarks.sim.race import main


def test_bench_race_json_reports_every_driver(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("torch")
    assert main(["--json", "--window", "12", "--repeat", "1"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["track"] == "hairpin-circuit"
    rows = {row["driver"]: row for row in report["races"]}
    assert list(rows) == ["reference", "vector", "lidar", "camera"]
    assert rows["reference"]["laps"] == 1 and rows["reference"]["target_seconds"] is None
    # Every tick of a benchmark race is a driven step (no penalty holds).
    assert all(row["driven_steps"] == 12 * 15 for row in rows.values())
    assert rows["camera"]["target_seconds"] == 1.0
    assert all(row["seconds_per_race"] > 0 for row in rows.values())

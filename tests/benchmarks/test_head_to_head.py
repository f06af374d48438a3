"""The head-to-head benchmark keeps working (figures are printed, never judged here)."""

from __future__ import annotations

import json

import pytest

from benchmarks.sim.head_to_head import main


def test_a_short_run_reports_every_race_and_the_issues_targets(
    capsys: pytest.CaptureFixture[str],
) -> None:
    pytest.importorskip("torch")
    assert main(["--json", "--window", "6", "--repeat", "1"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [(row["race"], row["cars"]) for row in report["races"]] == [
        ("camera, one car", 1),
        ("camera, two cars", 2),
        ("vector, six cars", 6),
    ]
    assert all(row["seconds_per_race"] > 0 for row in report["races"])
    one, two, _ = report["races"]
    assert report["camera_two_cars_ratio"] == pytest.approx(
        two["seconds_per_race"] / one["seconds_per_race"], rel=0.01
    )
    assert (report["camera_target_ratio"], report["vector_target_seconds"]) == (2.0, 1.0)

"""The league benchmark script keeps working (figures are printed, never judged here)."""

from __future__ import annotations

import json

import pytest

from benchmarks.league.board import main


def test_bench_json_reports_every_figure(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--json", "--racers", "30", "--submissions", "60", "--nights", "2"]
    assert main([*args, "--racers-per-night", "5", "--repeat", "1"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["submission_laps"] == 600
    assert report["races"] == 10
    assert set(report["timings_ms"]) == {"leaderboard", "standings", "submit", "submit_store_only"}
    assert all(value > 0 for value in report["timings_ms"].values())
    assert report["leaderboard_rows"] > 0
    assert report["db_bytes"] > 0


def test_bench_table(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--racers", "10", "--submissions", "20", "--nights", "1", "--racers-per-night", "3"]
    assert main([*args, "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    for label in ("leaderboard, one track", "season standings", "submit", "database file"):
        assert label in out

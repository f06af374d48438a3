"""The sync benchmark script keeps working (figures are printed, never judged here)."""

from __future__ import annotations

import json

import pytest

from benchmarks.league.sync import main


def test_bench_pushes_pulls_and_proves_a_second_push_sends_nothing(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["--json", "--records", "12", "--laps", "2"]) == 0
    results = json.loads(capsys.readouterr().out)
    assert [result["store"] for result in results] == ["dir", "dynamodb"]
    for result in results:
        assert result["pushed"] == result["pulled"] == result["records"] > 12
        assert (result["second_push_considered"], result["second_push_pushed"]) == (0, 0)
        assert result["same_leaderboard"] is True


def test_bench_table(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--stores", "dir", "--records", "5", "--laps", "1"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].startswith("dir ") and "0 to send, 0 written" in out

"""The trust benchmark at a small size: every attack of issue 41 held on both store kinds."""

from __future__ import annotations

import pytest

from benchmarks.league.trust import ATTACKS, main, run


@pytest.mark.slow
def test_no_attack_reaches_a_board_or_a_league_and_honest_results_stay() -> None:
    rows = run(["dir", "dynamodb"], window=10.0)
    assert len(rows) == 2 * len(ATTACKS)
    failed = [
        f"{row['store']}: {row['attack']} -> {row.get('error') or row['in_league_of']}"
        for row in rows
        if not row["held"]
    ]
    lost = [f"{row['store']}: {row['attack']}" for row in rows if not row["honest_kept"]]
    assert not failed, failed
    assert not lost, lost


def test_the_table_names_each_attack_and_the_target(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--stores", "dir", "--window", "10", "--only", "unadmitted"]) == 0
    out = capsys.readouterr().out
    assert "an unadmitted key pushes" in out
    assert "target: every attack held" in out
    assert "held 1 of 1 (target 1)" in out

"""Issue 47's camera benchmark: its table puts every figure beside the one before and the
issue's target, and a `--before` file that is not its own output is one sentence. (The
runs themselves take minutes: they are the benchmark's, not the tests'.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.training.camera import ISSUE_BEFORE, _print, main


def test_the_table_shows_before_now_and_the_issues_targets(
    capsys: pytest.CaptureFixture[str],
) -> None:
    result = {
        "before": ISSUE_BEFORE,
        "processes": 2,
        "seconds": 120.0,
        "training": {"steps_per_second_1": 633.0, "steps_per_second_2": 950.0, "ratio": 1.5},
        "race_seconds": 3.31,
        "race_seconds_runtime_1": 7.91,
        "steps_ratio_to_before": 1.5,
        "line": {
            "minutes": 15.0,
            "laps": "5/5",
            "best_over_limit_percent": 6.1,
            "mean_over_limit_percent": None,
        },
    }
    _print(result)
    out = capsys.readouterr().out
    for words in (
        "422",
        "633 (1.50x)",
        ">= 3x before",
        "1.48x",
        ">= 1.8x",
        "2.46 s",
        "3.31 s",
        "< 1 s",
        "same, torch runtime 1",
        "7.91 s (2.39x)",
        "+7.8%",
        "+6.1% (5/5 laps)",
        "aim +5%",
    ):
        assert words in out


def test_a_before_file_that_is_not_its_output_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    wrong = tmp_path / "before.json"
    wrong.write_text('{"rows": []}', encoding="utf-8")
    with pytest.raises(SystemExit) as exited:
        main(["--before", str(wrong), "--no-line"])
    assert exited.value.code == 2
    assert "is not the --json output of this benchmark" in capsys.readouterr().err

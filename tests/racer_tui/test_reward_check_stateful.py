"""`racer-tui reward check` calls the function as DeepRacer training would."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from racer_tui.cli.main import main
from tests.sim.test_reward_per_car import STATEFUL

COUNTING = """
calls = []


def reward_function(params):
    calls.append(params["steps"])
    return float(len(calls))
"""


def _check(capsys: pytest.CaptureFixture[str], path: Path) -> tuple[int, dict[str, float], str]:
    code = main(["reward", "check", str(path), "--track", "beginner-oval", "--json"])
    out, err = capsys.readouterr()
    return code, json.loads(out) if out else {}, err


def test_a_function_that_checks_steps_passes_the_check(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "stateful.py"
    path.write_text(STATEFUL, encoding="utf-8")
    code, report, err = _check(capsys, path)
    assert code == 0, err
    assert report["lap_steps"] > 50


def test_the_lap_starts_on_a_fresh_module_and_skips_the_prepare_step(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "counting.py"
    path.write_text(COUNTING, encoding="utf-8")
    code, report, _ = _check(capsys, path)
    assert code == 0
    # The sample call's module is not the lap's: the lap's first call is its call 1.
    assert report["lap_reward_min"] == 1.0
    assert report["lap_reward_max"] == report["lap_steps"]

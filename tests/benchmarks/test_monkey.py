"""The app monkey's long run runs end to end and prints every figure beside its target (the
figures are the benchmark's to report, not this test's to judge)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.app.monkey import print_report
from tests.conftest import REPO_ROOT


def test_a_short_monkey_run_reports_every_figure(
    racer_home: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A subprocess, as it is run: it changes the working folder and the data home.
    env = {**os.environ, "RACER_TUI_HOME": str(racer_home), "TMPDIR": str(tmp_path)}
    command = [sys.executable, "-m", "benchmarks.app.monkey", "--actions", "8", "--seed", "5"]
    run = subprocess.run(
        [*command, "--json"],
        check=False,
        cwd=REPO_ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["actions"] == 8
    assert report["crashes"] == []
    assert report["targets"] == {"crashes": 0, "actions": 100_000}
    assert report["rss_mb"]["start"] > 0 and report["rss_mb"]["end"] > 0
    assert report["slowest_action"]["action"]
    assert not (racer_home / "models").exists()  # the scratch home, never the racer's

    print_report(report)  # what the run prints without --json (one run of the app is enough)
    printed = capsys.readouterr().out
    assert "crashes" in printed and "target: 0" in printed
    assert "slowest action" in printed and "RSS" in printed

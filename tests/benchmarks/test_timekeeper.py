"""The timekeeper's latency benchmark runs end to end and reports its figures (never judged
here: they are the benchmark's to print)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.conftest import REPO_ROOT


def test_a_short_run_reports_each_conditions_latencies(tmp_path: Path) -> None:
    # A subprocess: the long-running app freezes objects out of garbage collection.
    command = [sys.executable, "-m", "benchmarks.app.timekeeper", "--keys", "4"]
    run = subprocess.run(
        [*command, "--no-training", "--json"],
        cwd=REPO_ROOT,
        env={**os.environ, "TMPDIR": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=180,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert list(report["latency_ms"]) == ["idle", "simulated heat in the app"]
    for figures in report["latency_ms"].values():
        assert figures["count"] == 4 and 0.0 < figures["p50"] <= figures["p95"] <= figures["max"]
    assert report["heats_raced_beside"] >= 0

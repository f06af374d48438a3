"""The live page's load benchmark runs end to end: viewers connect, see the timekeeper's
laps, and the figures are reported (never judged here: they are the benchmark's)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.conftest import REPO_ROOT


def test_a_short_run_reports_every_figure(tmp_path: Path) -> None:
    small = ["--viewers", "4", "--keys", "6", "--json"]
    run = subprocess.run(
        [sys.executable, "-m", "benchmarks.web.live_load", *small],
        cwd=REPO_ROOT,
        env={**os.environ, "TMPDIR": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=180,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["key_latency_ms"]["count"] == 6
    # Three laps captured, each seen by all four viewers, unless the next heat replaced the
    # heat before a stream showed its last lap (then for every viewer: they share polls).
    seen, superseded = report["viewers_behind_ms"]["count"], report["laps_superseded"]
    assert seen + superseded == 12 and superseded in (0, 4)
    assert report["viewers_behind_ms"]["max"] > 0
    assert 0 <= report["server_core_share"] < 2
    assert report["server_rss_mb"]["end"] > 0 and report["events_per_viewer"]["p50"] >= 3

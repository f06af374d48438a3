"""The soak benchmark runs end to end and reports every figure (never how fast anything is:
the figures are the benchmark's to print, not this test's to judge)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from tests.conftest import REPO_ROOT


def assert_latencies(figures: dict[str, Any]) -> None:
    assert figures["count"] > 0
    assert 0.0 <= figures["p50"] <= figures["p95"] <= figures["max"]


def test_a_short_soak_reports_every_figure(racer_home: Path, tmp_path: Path) -> None:
    # A subprocess: the long-running app freezes start-up objects out of garbage
    # collection and the benchmark hooks gc.callbacks, neither of which belongs in the
    # test process. TMPDIR keeps its temporary data home under this test's folder.
    env = {**os.environ, "RACER_TUI_HOME": str(racer_home), "TMPDIR": str(tmp_path)}
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.app.soak",
            "--actions",
            "60",
            "--no-training",
            "--json",
        ],
        cwd=REPO_ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=180,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)

    assert report["actions"] == 60
    assert report["warmup_actions"] == 50
    assert report["measured_actions"] == 10
    counts = report["action_counts"]
    assert sum(counts.values()) == 60
    # Switches are the majority; the first sync and heat come early, inside 60 actions.
    assert counts["switch"] > 60 // 2
    for kind in ("help", "delete-question", "projector", "sort", "sync", "heat"):
        assert counts[kind] > 0, kind
    assert report["heat_simulation_s"]["count"] > 0
    assert report["sync_s"]["count"] > 0

    for name in ("rss_mb", "rss_at_rest_mb", "objects"):
        for moment in ("after_warmup", "halfway", "end"):
            assert report[name][moment] > 0, (name, moment)
        for growth in ("growth_per_1000_actions", "second_half_growth_per_1000_actions"):
            assert isinstance(report[name][growth], float), (name, growth)
    assert report["objects"]["frozen_at_end"] > 0  # the long-running app froze them
    assert len(report["rss_mb"]["samples"]) > 0
    # At rest, free memory has gone back to the system: never more than the RSS just before.
    for moment in ("after_warmup", "halfway", "end"):
        assert report["rss_at_rest_mb"][moment] <= report["rss_mb"][moment] + 0.5, moment

    gc_figures = report["gc"]
    assert gc_figures["longest_pause_ms"] >= 0.0
    assert gc_figures["full_collections"] >= 0
    assert gc_figures["collections"] >= gc_figures["full_collections"]
    # A terminal's key can meet a whole collection: the worst is that pause and an answer.
    worst = gc_figures["longest_pause_ms"] + report["key_latency_ms"]["p50"]
    assert abs(report["terminal_key_worst_ms"] - worst) <= 0.1

    assert_latencies(report["key_latency_ms"])
    assert_latencies(report["section_switch_latency_ms"])
    for figures in report["latency_by_key_ms"].values():
        assert_latencies(figures)
    assert report["displays"] > 0

    assert report["ended_on_section"] is True
    assert report["machine"]["cpus"] > 0
    assert report["training"] == {"ran": False}
    assert any("--no-training" in note for note in report["notes"])
    assert report["targets"] == {
        "growth_mb_per_1000_actions_under": 1.0,
        "key_p95_ms_under": 50.0,
        "key_max_ms_under": 100.0,
    }
    # The temporary data home is removed afterwards.
    assert not any(path.name.startswith("racer-soak-") for path in tmp_path.iterdir())

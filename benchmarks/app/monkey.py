"""The app monkey, long: random input against the real app for many actions (issue 42).

`python -m benchmarks.app.monkey [--actions 100000] [--seed 1] [--json]`

Runs `racer_tui.app.monkey` (keys from a weighted alphabet, bursts queued as a terminal
delivers them, pastes, clicks at random cells, resizes between 60x20 and 200x60; after each
action: nothing raised, the app runs, the screen renders) in a scratch data home, and prints
the actions, the crashes (each with the actions that led to it and the app's crash report),
the slowest action, and this process's memory at the start, after a warm-up, halfway and
at the end (torch, which the first race or evaluation imports, is imported before the
start), each beside the issue's target. Textual's and rich's layout caches (LRU, at most
4,096 entries each) fill over the first thousand or two actions, faster with random
terminal sizes; a cache levels off, so the second half's growth is the one that shows a
leak. The exit code is 0 whenever the benchmark ran, crashes or not
(the figures say); 1 with one sentence on stderr when it could not run.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import sys
import time
from typing import Any

from racer_tui.app.monkey import MonkeyRun, rss_mb, run_monkey, scratch_home

DEFAULT_ACTIONS = 100_000
TARGET_CRASHES = 0
TARGET_ACTIONS = 100_000
PROGRESS_EVERY = 1_000


def report_of(run: MonkeyRun, real_training: bool) -> dict[str, Any]:
    measured = max(run.actions - run.warmup_actions, 1)
    growth = (run.rss_end_mb - run.rss_after_warmup_mb) / measured * 1000.0
    second_half = max(run.actions - run.halfway_actions, 1)
    growth_late = (run.rss_end_mb - run.rss_halfway_mb) / second_half * 1000.0
    return {
        "seed": run.seed,
        "actions": run.actions,
        "wall_seconds": round(run.seconds, 1),
        "crashes": [
            {
                "after_action": crash.action_number,
                "error": crash.error,
                "last_actions": crash.recent_actions,
                "report": crash.report_text or None,
                "traceback": crash.traceback,
            }
            for crash in run.crashes
        ],
        "apps_started": run.apps_started,
        "quits": run.quits,
        "slowest_action": {"action": run.slowest_action, "ms": round(run.slowest_ms, 1)},
        "rss_mb": {
            "start": round(run.rss_start_mb, 1),
            "after_warmup": round(run.rss_after_warmup_mb, 1),
            "warmup_actions": run.warmup_actions,
            "halfway": round(run.rss_halfway_mb, 1),
            "halfway_actions": run.halfway_actions,
            "end": round(run.rss_end_mb, 1),
            "growth_per_1000_actions": round(growth, 2),
            "growth_per_1000_actions_second_half": round(growth_late, 2),
        },
        "action_kinds": dict(run.kinds),
        "screens": dict(run.screens.most_common()),
        "training": "real worker" if real_training else "stand-in child (exits at once)",
        "targets": {"crashes": TARGET_CRASHES, "actions": TARGET_ACTIONS},
        "load_average_end": round(os.getloadavg()[0], 2),
    }


def print_report(report: dict[str, Any]) -> None:
    crashes = report["crashes"]
    rss = report["rss_mb"]
    slowest = report["slowest_action"]
    rows = [
        ("actions", f"{report['actions']:,}", f"{TARGET_ACTIONS:,}"),
        ("crashes", str(len(crashes)), str(TARGET_CRASHES)),
        ("slowest action", f"{slowest['ms']:,.0f} ms  ({slowest['action']})", ""),
        (
            f"RSS start / after {rss['warmup_actions']} / {rss['halfway_actions']:,} actions / end",
            f"{rss['start']:.0f} / {rss['after_warmup']:.0f} / {rss['halfway']:.0f} / "
            f"{rss['end']:.0f} MB",
            "flat",
        ),
        (
            "RSS growth per 1,000 actions after",
            f"{rss['growth_per_1000_actions']:+.2f} MB",
            "flat (soak: < 1 MB)",
        ),
        (
            "  in the second half",
            f"{rss['growth_per_1000_actions_second_half']:+.2f} MB",
            "flat: caches level off, a leak does not",
        ),
        ("apps started (after a quit or crash)", str(report["apps_started"]), ""),
        ("wall time", f"{report['wall_seconds']:,.0f} s", ""),
    ]
    print(f"app monkey, seed {report['seed']}, training: {report['training']}")
    for name, value, target in rows:
        beside = f"   target: {target}" if target else ""
        print(f"  {name:<38} {value}{beside}")
    print("  screens visited: " + ", ".join(f"{k} {v}" for k, v in report["screens"].items()))
    for crash in crashes:
        print(f"\ncrash after action {crash['after_action']}: {crash['error']}")
        print("  last actions: " + " | ".join(crash["last_actions"]))
        print("  " + crash["traceback"].rstrip().replace("\n", "\n  "))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--actions", type=int, default=DEFAULT_ACTIONS)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--screenshot-every",
        type=int,
        default=1,
        help="export the screen as SVG every N actions (1: after every action)",
    )
    parser.add_argument(
        "--real-training",
        action="store_true",
        help="let a training started in the app run the real worker (default: a stand-in)",
    )
    parser.add_argument("--json", action="store_true", help="one JSON object")
    args = parser.parse_args(argv)
    if args.actions < 1:
        parser.error("--actions must be at least 1")
    started = time.perf_counter()

    told = 0

    def progress(run: MonkeyRun) -> None:
        # Each crash is told as it is found: a run of hours that is stopped early (or a
        # crash whose cause is the machine, not the app) is read from the log, not the end.
        nonlocal told
        for crash in run.crashes[told:]:
            print(
                f"  crash at action {crash.action_number:,}: {crash.error}\n"
                f"    after: {' | '.join(crash.recent_actions)}\n"
                + "".join(f"    {line}\n" for line in crash.traceback.splitlines()),
                file=sys.stderr,
                flush=True,
            )
        told = len(run.crashes)
        if run.actions % PROGRESS_EVERY == 0:
            print(
                f"  {run.actions:,} actions, {len(run.crashes)} crashes, "
                f"{time.perf_counter() - started:,.0f} s, RSS {rss_mb():,.0f} MB",
                file=sys.stderr,
                flush=True,
            )

    # The first race or evaluation of a model imports torch (about 200 MB), once: imported
    # before the start, so that the memory figures say what the actions leave behind.
    import sim.training.policy  # noqa: F401

    try:
        with scratch_home(real_training=args.real_training):
            run = asyncio.run(
                run_monkey(
                    args.actions,
                    args.seed,
                    screenshot_every=args.screenshot_every,
                    on_progress=progress,
                )
            )
    except Exception as error:
        print(
            f"benchmarks.app.monkey: the benchmark could not run: {type(error).__name__}: {error}",
            file=sys.stderr,
        )
        return 1
    report = report_of(run, args.real_training)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print_report(report)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

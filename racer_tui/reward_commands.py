"""`racer-tui reward check FILE`: does this reward function work, and what does it pay?

It runs the function on DeepRacer-complete sample params, then scores every step of the
reference driver's lap on a track, so a racer sees real values before training. The
function runs in a child process with a time limit (sim.reward_probe).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np
from rich.table import Table
from rich.text import Text

from racer_tui.output import print_json, print_table
from sim.reward_function import read_reward_file
from sim.reward_probe import check_reward_source
from sim.track_catalog import DEFAULT_TRACK, resolve_track

NAMES = ("reward",)


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    reward = commands.add_parser("reward", help="check a reward function")
    reward_commands = reward.add_subparsers(dest="reward_command", metavar="ACTION", required=True)
    check = reward_commands.add_parser("check", help="run a reward function on sample params")
    check.add_argument("file", help="Python file defining reward_function(params)")
    check.add_argument(
        "--track", default=None, help=f"score a reference lap on this track ({DEFAULT_TRACK})"
    )
    check.add_argument("--json", action="store_true")


def run(args: argparse.Namespace) -> int:
    source = read_reward_file(Path(args.file))
    track_name = args.track or DEFAULT_TRACK
    resolve_track(track_name)  # an unknown track is the racer's typo, said before any run
    # In a child process with a time limit on every call: a function that loops, sleeps or
    # exits its process is reported in one sentence, and never hangs this command.
    probe = check_reward_source(source, str(args.file), track=track_name)
    lap_rewards = probe.lap_rewards or (0.0,)
    report: dict[str, Any] = {
        "file": str(args.file),
        "sample_params_reward": probe.sample_reward,
        "track": probe.track,
        "lap_steps": len(probe.lap_rewards),
        "lap_reward_min": float(np.min(lap_rewards)),
        "lap_reward_mean": float(np.mean(lap_rewards)),
        "lap_reward_max": float(np.max(lap_rewards)),
        "lap_reward_total": float(np.sum(probe.lap_rewards)),
    }
    if args.json:
        print_json(report)
        return 0
    table = Table(title=Text(f"Reward check: {args.file}"), show_header=False)
    table.add_column("what")
    table.add_column("value", justify="right")
    table.add_row("sample params", f"{probe.sample_reward:.4f}")
    table.add_row(Text(f"reference lap on {probe.track}"), f"{len(probe.lap_rewards)} steps")
    for key in ("min", "mean", "max", "total"):
        table.add_row(f"  reward {key}", f"{report['lap_reward_' + key]:.4f}")
    print_table(table)
    print("OK: the function ran on every step without an error.")
    return 0

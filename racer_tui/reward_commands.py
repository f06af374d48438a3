"""`racer-tui reward check FILE`: does this reward function work, and what does it pay?

It runs the function on DeepRacer-complete sample params, then scores every step of the
reference driver's lap on a track, so a racer sees real values before training.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np
from rich.table import Table
from rich.text import Text

from racer_tui.output import print_json, print_table
from sim.reference_driver import ReferenceDriver
from sim.reward_function import RewardFunction, load_reward_function
from sim.reward_sample_params import sample_params
from sim.simulation import EpisodeStatus, TrackSimulation
from sim.track import Track
from sim.track_catalog import DEFAULT_TRACK, resolve_track

_MAX_LAP_STEPS = 15 * 120


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
    reward = load_reward_function(Path(args.file))
    sample_value = reward(sample_params())
    track_name = args.track or DEFAULT_TRACK
    track = resolve_track(track_name)
    # The lap runs on the file loaded afresh, as a DeepRacer worker starts with it: state the
    # sample call left in the module does not leak into the lap.
    lap_rewards = _score_reference_lap(reward.fresh(), track)
    report: dict[str, Any] = {
        "file": str(args.file),
        "sample_params_reward": sample_value,
        "track": track.name,
        "lap_steps": len(lap_rewards),
        "lap_reward_min": float(np.min(lap_rewards)),
        "lap_reward_mean": float(np.mean(lap_rewards)),
        "lap_reward_max": float(np.max(lap_rewards)),
        "lap_reward_total": float(np.sum(lap_rewards)),
    }
    if args.json:
        print_json(report)
        return 0
    table = Table(title=Text(f"Reward check: {args.file}"), show_header=False)
    table.add_column("what")
    table.add_column("value", justify="right")
    table.add_row("sample params", f"{sample_value:.4f}")
    table.add_row(Text(f"reference lap on {track.name}"), f"{len(lap_rewards)} steps")
    for key in ("min", "mean", "max", "total"):
        table.add_row(f"  reward {key}", f"{report['lap_reward_' + key]:.4f}")
    print_table(table)
    print("OK: the function ran on every step without an error.")
    return 0


def _score_reference_lap(reward: RewardFunction, track: Track) -> list[float]:
    sim = TrackSimulation(track, 1)
    driver = ReferenceDriver(track)
    sim.reset_car(0, start_s=0.0)
    rewards: list[float] = []
    for _ in range(_MAX_LAP_STEPS):
        sim.apply(*driver.act(sim))
        if sim.steps[0] > 1:  # step 1 is DeepRacer's prepare step: the function is not called
            rewards.append(float(reward(sim.all_params()[0])))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    return rewards

"""Race benchmark: how long a full 4-minute time trial takes to simulate, per driver.

    python -m benchmarks.sim.race [--json] [--track NAME] [--window S] [--repeat N]

Rows: the reference driver, and a policy per sensor (vector, lidar, camera 160x120) when
torch and `sim.training.policy` are there. A policy costs the same to run trained or
untrained, so each is a fresh network for a default model with that sensor. Policy races
run with a zero off-track penalty: an untrained car leaves the track often, and penalty
holds (no stepping) would hide the cost being measured, so every tick is a driven step.

Figures are printed, never judged: the targets are the issues' (every policy <= 1 s a
race; a camera race under 1.0 s is issue 47's), and the machine's load moves the figures.
Wall-clock and CPU seconds are both shown; on a busy machine the CPU figure is the
steadier one.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

from sim.race.driver import Driver, reference_driver
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

POLICY_SENSORS = ("vector", "lidar", "camera")
TARGET_SECONDS: dict[str, float | None] = {
    "reference": None,
    "vector": 1.0,
    "lidar": 1.0,
    "camera": 1.0,
}


@dataclass(frozen=True)
class Timing:
    driver: str
    wall_seconds: float  # best of the repeats
    cpu_seconds: float
    driven_steps: int
    laps: int
    target_seconds: float | None

    def to_json(self, window: float) -> dict[str, Any]:
        return {
            "driver": self.driver,
            "seconds_per_race": round(self.wall_seconds, 3),
            "cpu_seconds_per_race": round(self.cpu_seconds, 3),
            "times_real_time": round(window / self.wall_seconds, 1),
            "driven_steps": self.driven_steps,
            "steps_per_s": round(self.driven_steps / self.wall_seconds),
            "laps": self.laps,
            "target_seconds": self.target_seconds,
            "meets_target": None
            if self.target_seconds is None
            else self.wall_seconds <= self.target_seconds,
        }


def policy_driver(track: Track, sensor: str) -> Driver | None:
    """An untrained policy for a default model with `sensor`; None without torch."""
    try:
        import torch

        from sim.deepracer.files import ModelMetadata
        from sim.training.policy import build_network
        from sim.training.policy_driver import PolicyDriver
    except ImportError:
        return None
    # One thread: a batch of one is too small to share between cores.
    torch.set_num_threads(1)
    torch.manual_seed(0)
    metadata = ModelMetadata(_default_action_space(), (sensor,))
    network = build_network(metadata)
    return PolicyDriver(network, metadata, name=f"{sensor}-policy", content_hash=sensor)


def _default_action_space() -> Any:
    try:
        from sim.garage.options import default_action_space

        return default_action_space()
    except ImportError:
        from sim.deepracer.action_space import discrete_grid

        return discrete_grid(30.0, 5, 3.0, 2)


def time_race(
    name: str, track: Track, make_driver: Callable[[], Driver], window: float, repeat: int
) -> Timing:
    rules = RaceRules(window_seconds=window, penalty_seconds=0.0)
    driver = make_driver()
    # A short race first: racing lines, rasters and lookup tables are built once per track.
    run_race(track, RaceRules(window_seconds=10.0), driver)
    best_wall, best_cpu = float("inf"), float("inf")
    result = None
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = run_race(track, rules, driver)
        best_wall = min(best_wall, time.perf_counter() - wall)
        best_cpu = min(best_cpu, time.process_time() - cpu)
    assert result is not None and result.trace is not None
    driven = sum(1 for status in result.trace.statuses() if status not in ("prepare", "pause"))
    return Timing(name, best_wall, best_cpu, driven, len(result.laps), TARGET_SECONDS[name])


def run(track: Track, window: float, repeat: int) -> list[Timing]:
    timings = [time_race("reference", track, lambda: reference_driver(track), window, repeat)]
    for sensor in POLICY_SENSORS:
        driver = policy_driver(track, sensor)
        if driver is None:
            break
        timings.append(time_race(sensor, track, partial(_same, driver), window, repeat))
    return timings


def _same(driver: Driver) -> Driver:
    return driver


def _print_table(track: Track, window: float, timings: Sequence[Timing]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"One {window:g} s race on {track.name}, single process")
    for column in ("driver", "s/race", "cpu s", "x real time", "steps/s", "target", "meets"):
        table.add_column(column, justify="right")
    for timing in timings:
        row = timing.to_json(window)
        target = "-" if timing.target_seconds is None else f"<= {timing.target_seconds:g} s"
        meets = "-" if row["meets_target"] is None else ("yes" if row["meets_target"] else "NO")
        table.add_row(
            timing.driver if timing.driver == "reference" else f"{timing.driver} policy",
            f"{timing.wall_seconds:.3f}",
            f"{timing.cpu_seconds:.3f}",
            f"{row['times_real_time']:g}",
            f"{row['steps_per_s']:,}",
            target,
            meets,
        )
    Console().print(table)
    if len(timings) == 1:
        Console().print("torch is not installed: policy rows skipped.")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sim.race", description=(__doc__ or "").split("\n")[0]
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--track", default="hairpin-circuit", help="track name or .npy file")
    parser.add_argument("--window", type=float, default=240.0, help="race window, seconds")
    parser.add_argument("--repeat", type=int, default=2, help="races timed per driver (best)")
    args = parser.parse_args(argv)
    track = resolve_track(args.track)
    timings = run(track, args.window, max(1, args.repeat))
    if args.json:
        document = {
            "track": track.name,
            "window_seconds": args.window,
            "races": [timing.to_json(args.window) for timing in timings],
        }
        sys.stdout.write(json.dumps(document, indent=2) + "\n")
    else:
        _print_table(track, args.window, timings)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Head-to-head benchmark: how long a 4-minute race of several cars takes to simulate.

    python -m benchmarks.sim.head_to_head [--json] [--track NAME] [--window S] [--repeat N]

Rows (issue 46's speed targets, printed beside the figures):
- camera: one car's race, then two cars of the same model racing each other (their frames
  rendered and their policy run in one batch); the ratio is measured in this one run, and
  the target is under 2x;
- vector: six cars of the same model; the target is under 1 s a race.

The policies are fresh networks of a default model for the sensor, as in
`benchmarks.sim.race` (a policy costs the same to run trained or untrained). The races run
for the whole window with no penalty, so every tick is a driven step for every car.
Figures are printed, never judged; wall-clock and CPU seconds are both shown.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from benchmarks.sim.race import policy_driver
from sim.race.driver import Driver
from sim.race.engine import run_race
from sim.race.head_to_head import Entry, run_head_to_head
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

TARGET_CAMERA_RATIO = 2.0  # a 2-car camera race against one car's
TARGET_VECTOR_SECONDS = 1.0  # a 6-car vector race


@dataclass(frozen=True)
class Timing:
    label: str
    cars: int
    wall_seconds: float  # best of the repeats
    cpu_seconds: float

    def to_json(self) -> dict[str, Any]:
        return {
            "race": self.label,
            "cars": self.cars,
            "seconds_per_race": round(self.wall_seconds, 4),
            "cpu_seconds_per_race": round(self.cpu_seconds, 4),
        }


def _rules(window: float) -> RaceRules:
    # Head-to-head's own rules, for the whole window and without holds.
    return RaceRules(
        race_type=HEAD_TO_HEAD_RULES.race_type,
        window_seconds=window,
        penalty_seconds=0.0,
        collision_penalty_seconds=0.0,
        max_offtracks_per_lap=None,
    )


def _timed(label: str, cars: int, race: Any, repeat: int) -> Timing:
    race()  # racing lines, rasters and lookup tables are built once per track
    wall, cpu = float("inf"), float("inf")
    for _ in range(repeat):
        wall_0, cpu_0 = time.perf_counter(), time.process_time()
        race()
        wall = min(wall, time.perf_counter() - wall_0)
        cpu = min(cpu, time.process_time() - cpu_0)
    return Timing(label, cars, wall, cpu)


def _one_car(track: Track, driver: Driver, window: float, repeat: int) -> Timing:
    rules = RaceRules(window_seconds=window, penalty_seconds=0.0, max_offtracks_per_lap=None)
    return _timed(
        "camera, one car", 1, lambda: run_race(track, rules, driver, keep_trace=False), repeat
    )


def _together(
    label: str, track: Track, driver: Driver, cars: int, *, window: float, repeat: int
) -> Timing:
    entries = [Entry(f"car {k + 1}", driver) for k in range(cars)]
    rules = _rules(window)
    return _timed(label, cars, lambda: run_head_to_head(track, rules, entries), repeat)


def run(track: Track, window: float, repeat: int) -> dict[str, Any] | None:
    camera = policy_driver(track, "camera")
    vector = policy_driver(track, "vector")
    if camera is None or vector is None:
        return None
    one = _one_car(track, camera, window, repeat)
    two = _together("camera, two cars", track, camera, 2, window=window, repeat=repeat)
    six = _together("vector, six cars", track, vector, 6, window=window, repeat=repeat)
    ratio = two.wall_seconds / max(one.wall_seconds, 1e-9)
    return {
        "track": track.name,
        "window_seconds": window,
        "races": [timing.to_json() for timing in (one, two, six)],
        "camera_two_cars_ratio": round(ratio, 3),
        "camera_target_ratio": TARGET_CAMERA_RATIO,
        "vector_six_cars_seconds": round(six.wall_seconds, 4),
        "vector_target_seconds": TARGET_VECTOR_SECONDS,
    }


def _print(report: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    title = f"Head-to-head: one {report['window_seconds']:g} s race on {report['track']}"
    table = Table(title=title)
    for column in ("race", "cars", "s/race", "cpu s"):
        table.add_column(column, justify="right")
    for row in report["races"]:
        table.add_row(
            row["race"],
            str(row["cars"]),
            f"{row['seconds_per_race']:.3f}",
            f"{row['cpu_seconds_per_race']:.3f}",
        )
    console = Console()
    console.print(table)
    ratio, six = report["camera_two_cars_ratio"], report["vector_six_cars_seconds"]
    console.print(
        f"two camera cars: {ratio:.2f}x one car's race (target: under "
        f"{report['camera_target_ratio']:g}x)"
    )
    console.print(
        f"six vector cars: {six:.3f} s a race (target: under {report['vector_target_seconds']:g} s)"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sim.head_to_head", description=(__doc__ or "").split("\n")[0]
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--track", default="reinvent_base", help="track name or .npy file")
    parser.add_argument("--window", type=float, default=240.0, help="race window, seconds")
    parser.add_argument("--repeat", type=int, default=2, help="races timed each (best)")
    args = parser.parse_args(argv)
    report = run(resolve_track(args.track), args.window, max(1, args.repeat))
    if report is None:
        print("benchmarks.sim.head_to_head: torch is not installed.", file=sys.stderr)
        return 1
    if args.json:
        sys.stdout.write(json.dumps(report, indent=2) + "\n")
    else:
        _print(report)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Simulator benchmark: env steps per second per sensor, and reference laps per track.

    python -m benchmarks.sim.simulator [--json] [--track FILE ...] [--cars N] [--seconds S]

Steps per second are single-process: one Python process steps a batch of cars (the way
training runs), each car-step counting once; the single-car gymnasium env is reported
beside it. Each sensor is timed in a time trial and among DeepRacer's objects: 3 boxes
(object avoidance) and 3 bot cars changing lanes (head-to-bot), each car its own. Figures
are printed, never judged: the targets are in the issue, and the machine's load moves them.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from sim.env import BatchedDeepRacer, DeepRacerEnv, EnvConfig
from sim.physics.objects.settings import BotSettings, ObstacleSettings, RaceSettings, RaceType
from sim.physics.reference_driver import reference_lap
from sim.sensors.observations import SensorOptions
from sim.tracks.catalog import list_tracks, resolve_track
from sim.tracks.track import Track, load_track

TARGETS = {"vector": 30_000, "lidar": 12_000, "camera": 6_000}
# The race types timed for every sensor (the goal: objects cost at most 30 %).
RACES: dict[str, RaceSettings | None] = {
    "time trial": None,
    "3 boxes": RaceSettings(RaceType.OBJECT_AVOIDANCE, obstacles=ObstacleSettings(count=3)),
    "3 bots": RaceSettings(
        RaceType.HEAD_TO_BOT, bots=BotSettings(count=3, speed=1.0, lane_change=True)
    ),
}


def _cautious_actions(rng: np.random.Generator, n: int) -> np.ndarray:
    """Normalised continuous actions: gentle steering, 0.1-1.1 m/s."""
    steering = rng.uniform(-0.3, 0.3, size=n)
    speed = rng.uniform(-1.0, -0.5, size=n)
    return np.stack([steering, speed], axis=1).astype(np.float32)


def batched_steps_per_second(
    track: Track, sensor: str, cars: int, seconds: float, race: RaceSettings | None = None
) -> float:
    config = EnvConfig.build(track, sensors=(sensor,), sensor_options=SensorOptions(), race=race)
    env = BatchedDeepRacer(config, cars)
    env.reset()
    rng = np.random.default_rng(0)
    # A cautious policy (slow-ish, mostly straight) keeps episodes long, like a policy
    # that has started to learn; pure noise would measure resets instead of steps.
    steps = 0
    started = time.perf_counter()
    while time.perf_counter() - started < seconds:
        env.step(_cautious_actions(rng, cars))
        steps += cars
    return steps / (time.perf_counter() - started)


def single_env_steps_per_second(
    track: Track, sensor: str, seconds: float, race: RaceSettings | None = None
) -> float:
    env = DeepRacerEnv(EnvConfig.build(track, sensors=(sensor,), race=race))
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    steps = 0
    started = time.perf_counter()
    while time.perf_counter() - started < seconds:
        _, _, terminated, truncated, _ = env.step(_cautious_actions(rng, 1)[0])
        steps += 1
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - started)


def run(tracks: list[Track], cars: int, seconds: float) -> dict[str, Any]:
    bench_track = tracks[0]
    sensors = []
    for sensor, target in TARGETS.items():
        trial_rate = math.nan
        for race_name, race in RACES.items():
            rate = batched_steps_per_second(bench_track, sensor, cars, seconds, race)
            single = single_env_steps_per_second(bench_track, sensor, seconds / 2, race)
            if race is None:
                trial_rate = rate
            sensors.append(
                {
                    "sensor": sensor if sensor != "camera" else "camera 160x120",
                    "race": race_name,
                    "cars_per_process": cars,
                    "steps_per_s": round(rate),
                    "single_env_steps_per_s": round(single),
                    # How much slower than the time trial (the goal: at most 30 %).
                    "slower_than_time_trial_percent": round((trial_rate / rate - 1.0) * 100, 1),
                    "target": target,
                    "meets_target": rate >= target,
                }
            )
    laps = []
    for track in tracks:
        lap = reference_lap(track)
        laps.append(
            {
                "track": track.name,
                "length_m": round(track.length, 2),
                "width_m": round(track.width, 3),
                "reference_lap_s": None if math.isnan(lap.lap_time) else round(lap.lap_time, 3),
                "status": lap.status,
                "avg_speed_m_s": None
                if math.isnan(lap.lap_time)
                else round(track.length / lap.lap_time, 2),
            }
        )
    return {"bench_track": bench_track.name, "sensors": sensors, "reference_laps": laps}


def _print_tables(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    table = Table(title=f"Env steps per second (one process, track {result['bench_track']})")
    for col in (
        "sensor",
        "race",
        "cars",
        "steps/s",
        "single env steps/s",
        "slower",
        "target",
        "meets",
    ):
        table.add_column(col, justify="right")
    for row in result["sensors"]:
        table.add_row(
            row["sensor"],
            row["race"],
            str(row["cars_per_process"]),
            f"{row['steps_per_s']:,}",
            f"{row['single_env_steps_per_s']:,}",
            "-" if row["race"] == "time trial" else f"{row['slower_than_time_trial_percent']}%",
            f"{row['target']:,}",
            "yes" if row["meets_target"] else "NO",
        )
    console.print(table)
    laps = Table(title="Reference laps (standing start, reference driver)")
    for col in ("track", "length", "width", "lap", "avg speed", "status"):
        laps.add_column(col, justify="right")
    for row in result["reference_laps"]:
        lap = "-" if row["reference_lap_s"] is None else f"{row['reference_lap_s']:.3f} s"
        speed = "-" if row["avg_speed_m_s"] is None else f"{row['avg_speed_m_s']:.2f} m/s"
        laps.add_row(
            row["track"],
            f"{row['length_m']:.2f} m",
            f"{row['width_m']:.3f} m",
            lap,
            speed,
            row["status"],
        )
    console.print(laps)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sim.simulator", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--track", action="append", default=[], help="also time this .npy track")
    parser.add_argument("--cars", type=int, default=64, help="cars stepped per process")
    parser.add_argument("--seconds", type=float, default=3.0, help="time per sensor measurement")
    args = parser.parse_args(argv)
    tracks = [resolve_track(info.name) for info in list_tracks() if info.builtin]
    tracks += [load_track(path) for path in args.track]
    result = run(tracks, args.cars, args.seconds)
    if args.json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
    else:
        _print_tables(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Benchmark the race view's drawing: frames per second and CPU used, at two terminal sizes.

`python -m benchmarks.app.race_view [--seconds 5] [--fps 30] [--json]`

The car's path is simulated before timing starts (the reference driver on a built-in
track), so the figures measure drawing alone: the app runs headless at 80x24 and
200x60, a timer feeds one car position per frame, and we count frames that reached the
screen and the process CPU time spent. Target: >= 20 frames/s with <= 25% of one core.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import time
from dataclasses import asdict, dataclass

import numpy as np
from textual.app import App, ComposeResult

from racer_tui.app.widgets.race_map import CarMarker, RaceMap
from sim.physics.car import STEP_HZ
from sim.physics.reference_driver import ReferenceDriver
from sim.physics.simulation import TrackSimulation
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

TRAIL_STEPS = 45  # three seconds of trail at 15 Hz


@dataclass(frozen=True)
class ViewFigures:
    size: str
    target_fps: float
    frames_per_second: float
    cpu_percent_of_one_core: float


def simulate_path(track: Track, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    sim = TrackSimulation(track, 1)
    driver = ReferenceDriver(track)
    sim.reset_car(0, start_s=0.0)
    xy, heading = [], []
    for _ in range(int(seconds * STEP_HZ)):
        sim.apply(*driver.act(sim))
        xy.append((float(sim.fleet.x[0]), float(sim.fleet.y[0])))
        heading.append(float(sim.heading_deg[0]))
        if sim.done[0]:
            sim.reset_car(0, start_s=0.0)
    return np.array(xy), np.array(heading)


class _ViewApp(App[None]):
    def __init__(self, track: Track) -> None:
        super().__init__()
        self.track = track

    def compose(self) -> ComposeResult:
        yield RaceMap(self.track)


async def _measure(
    track: Track,
    path: tuple[np.ndarray, np.ndarray],
    size: tuple[int, int],
    fps: float,
    seconds: float,
) -> ViewFigures:
    xy, heading = path
    app = _ViewApp(track)
    async with app.run_test(size=size) as pilot:
        view = app.query_one(RaceMap)
        await pilot.pause()
        frame = 0

        def tick() -> None:
            nonlocal frame
            i = frame % len(xy)
            view.show(
                CarMarker(float(xy[i, 0]), float(xy[i, 1]), float(heading[i])),
                trail=xy[max(0, i - TRAIL_STEPS) : i + 1],
                ghost=(float(xy[(i + 7) % len(xy), 0]), float(xy[(i + 7) % len(xy), 1])),
            )
            frame += 1

        view.frames_drawn = 0
        cpu0, wall0 = time.process_time(), time.perf_counter()
        timer = app.set_interval(1.0 / fps, tick)
        await asyncio.sleep(seconds)
        timer.stop()
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        drawn = view.frames_drawn
    return ViewFigures(
        size=f"{size[0]}x{size[1]}",
        target_fps=fps,
        frames_per_second=drawn / wall,
        cpu_percent_of_one_core=100.0 * cpu / wall,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--fps", type=float, default=30.0, help="frames offered per second")
    parser.add_argument("--track", default="grand-prix")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    track = resolve_track(args.track)
    path = simulate_path(track, 40.0)
    figures = [
        asyncio.run(_measure(track, path, size, args.fps, args.seconds))
        for size in ((80, 24), (200, 60))
    ]
    if args.json:
        print(json.dumps([asdict(f) for f in figures], indent=2))
        return 0
    print(f"race view on {track.name}, {args.fps:g} frames offered per second")
    print(f"{'size':>8} {'frames/s':>9} {'CPU % of a core':>16}   target: >= 20 frames/s, <= 25%")
    for f in figures:
        print(f"{f.size:>8} {f.frames_per_second:9.1f} {f.cpu_percent_of_one_core:16.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

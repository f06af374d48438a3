"""How long a reward map takes: `python -m benchmarks.sim.reward_map [--track T] [--json]`.

The figure the reward-map work is held to: a 0.1 m grid over reinvent_base with a plain
Python reward function (the follow_center_line template) in under 2 s. It times the grid,
the poses and the calls in this process (what the probe's child does after its start-up),
and the whole `reward map` round trip through the child process.
"""

from __future__ import annotations

import argparse
import json
import time

from sim.coach.reward_line import load_template, template_source
from sim.reward.map import MapOptions, compute_map
from sim.reward.probe import map_reward_source
from sim.reward.template_files import TEMPLATES
from sim.tracks.catalog import resolve_track

TARGET_SECONDS = 2.0
TEMPLATE = "follow_center_line"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--track", default="reinvent_base")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    track = resolve_track(args.track)
    options = MapOptions(spacing=0.1)
    reward = load_template(TEMPLATE)
    started = time.perf_counter()
    reward_map = compute_map(reward, track, options)
    in_process = time.perf_counter() - started
    started = time.perf_counter()
    map_reward_source(template_source(TEMPLATE), TEMPLATES[TEMPLATE], track.name, options)
    round_trip = time.perf_counter() - started
    figures = {
        "track": track.name,
        "cells": len(reward_map.shown),
        "compute_seconds": round(in_process, 3),
        "child_process_round_trip_seconds": round(round_trip, 3),
        "target_seconds": TARGET_SECONDS,
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"reward map of {track.name}, 0.1 m grid, {figures['cells']:,} cells")
    print(f"  computed in {in_process:.3f} s (target < {TARGET_SECONDS:g} s)")
    print(f"  through the child process, start-up included: {round_trip:.3f} s")


if __name__ == "__main__":
    main()

"""Limit-lap benchmark: the flying and standing limit laps of tracks beside the reference
driver's lap, how long each takes to compute, and how close the simulator drives them.

    python -m benchmarks.sim.limit_lap [TRACK ...] [--json]

Without tracks: every built-in track, and reinvent_base, Spain_track and
reInvent2019_track. Each limit lap is computed afresh (no cache) in this process, on one
core; the target is under 5 s for a 60 m track. The check drives the simulator along the
line at its speeds from rest (`sim.coach.tracking`) and gives the driven flying lap's gap
to the computed one (the issue asks within 3 %), and the car's mean distance from the line
over both laps. Figures are printed, never judged by the exit code.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from typing import Any

from sim.coach.limit_lap import compute_limit_lap
from sim.coach.limits import car_limits
from sim.coach.tracking import drive_line
from sim.physics.car import DEEPRACER_CAR
from sim.physics.reference_driver import reference_lap
from sim.tracks.catalog import list_tracks, resolve_track

OFFICIAL = ("reinvent_base", "Spain_track", "reInvent2019_track")
TARGET_SECONDS_PER_60_M = 5.0


def default_tracks() -> list[str]:
    built_in = [info.name for info in list_tracks() if info.kind == "built-in" and info.lappable]
    return [*built_in, *OFFICIAL]


def measure(name: str) -> dict[str, Any]:
    track = resolve_track(name)
    started = time.process_time()
    lap = compute_limit_lap(track, car_limits(), DEEPRACER_CAR)
    seconds = time.process_time() - started
    driven = drive_line(track, lap.points, lap.speeds, lap.curvature)
    reference = reference_lap(track)

    def rounded(value: float, digits: int = 3) -> float | None:
        return None if math.isnan(value) else round(value, digits)

    return {
        "track": track.name,
        "length_m": round(track.length, 2),
        "flying_s": rounded(lap.flying_seconds),
        "standing_s": rounded(lap.standing_seconds),
        "reference_s": rounded(reference.lap_time),
        "compute_cpu_s": round(seconds, 2),
        "driven_flying_s": rounded(driven.flying),
        "driven_standing_s": rounded(driven.standing),
        "driven_gap_percent": rounded((driven.flying / lap.flying_seconds - 1.0) * 100.0, 1),
        "driven_status": driven.status,
        "driven_off_line_m": rounded(driven.off_line),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.sim.limit_lap", description=__doc__)
    parser.add_argument("tracks", nargs="*", help="track names (default: see above)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = [measure(name) for name in args.tracks or default_tracks()]
    if args.json:
        print(json.dumps({"target_cpu_s_per_60_m": TARGET_SECONDS_PER_60_M, "tracks": rows}))
        return 0
    print(
        f"{'track':<20}{'length':>8}{'flying':>9}{'standing':>10}{'reference':>11}"
        f"{'cpu':>7}{'driven':>9}{'gap':>7}{'off line':>10}"
    )
    for row in rows:
        print(
            f"{row['track']:<20}{row['length_m']:>7.2f}m{_s(row['flying_s']):>9}"
            f"{_s(row['standing_s']):>10}{_s(row['reference_s']):>11}"
            f"{row['compute_cpu_s']:>6.2f}s{_s(row['driven_flying_s']):>9}"
            f"{_percent(row['driven_gap_percent']):>7}{_cm(row['driven_off_line_m']):>10}"
        )
    print(
        f"Target: under {TARGET_SECONDS_PER_60_M:g} s of one core for a 60 m track; the driven "
        "flying lap within 3 % of the computed one."
    )
    return 0


def _s(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def _cm(value: float | None) -> str:
    return "-" if value is None else f"{value * 100:.1f} cm"


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{value:+.1f}%"


if __name__ == "__main__":
    sys.exit(main())

"""The fastest lap any DeepRacer car could drive on a track, under DeepRacer's rules: the
floor under which a league accepts no lap (`sim.coach.plausible` says where it applies).

It is the coach's limit lap (`racing_line.optimise_line`, `speed_profile`) for a car more
able than any DeepRacer simulator's, on a road widened by what DeepRacer lets a car cut:

- What a car may cut. DeepRacer puts a car off track only when all four of its wheel
  centres are off the road (`is_offtrack`); while one of them is on the road the car is on
  track and its lap goes on. The car's centre is then no farther from the road than that
  wheel centre is from the car's centre, and every wheel centre is the same distance from
  it: the corners of the wheelbase x wheel-track rectangle (`CarSpec.wheel_offsets`),
  hypot(0.164 / 2, 0.160 / 2) = 0.115 m away. Nothing tighter holds: a car set across the
  border with one wheel centre just on the line has its centre 0.115 m beyond it. So the
  floor's line may go `cutting_reach()` beyond either border (the coach's own lines keep
  the car's half-width and a margin inside them). The road is widened along the centre
  line's normals, and never past where they cross on the inside of a bend (a folded frame
  gives a line with a kink no car could drive).
- How fast. DeepRacer's action space tops at 4 m/s, which its simulator drives 2 % faster
  (`CarSpec.speed_gain`): 4.08 m/s. The floor's car holds 10 m/s^2 sideways (DeepRacer's
  traces stay under about 7, racer-tui's car holds 7), speeds up at 15 m/s^2 and brakes
  at 20 (racer-tui's car: 10 and 15; its simapp 4 car: 4.4 and 18), turns 30 degrees on
  its geometric wheelbase with no tyre slip, understeer or steering lag (every
  simulator's car turns wider and later).
- Which line. The coach's own search (`optimise_line`), and beside it shorter lines
  (more weight on length, `LENGTH_SEARCH`): a car this able is held back more by its top
  speed than by its corners. The fastest of them is a line found, not a proven fastest
  one, so the floor is `SLACK` under its flying lap; where the coach's line turns tighter
  than even this car can, it is let round at its tightest turn's speed. A road the solver
  finds no line through at all gives no floor here: the caller falls back to the hull.
- And never under what no search is needed for: the shortest loop round the infield less
  the cut (`cut_loop_metres`) at 4.08 m/s.

Checked against the best line found the same way for racer-tui's car (without its
steering lag and understeer, so faster than it can drive): the floor is 8 to 18 % under
it on re:Invent 2018, A to Z Speedway, racer-tui's speedway, the ovals, the hairpin and
the long Albert and Belille. On re:Invent 2018 (reinvent_base) the floor is 4.140 s: the
coach's flying limit lap for racer-tui's car is 4.866 s, its best line found this way
4.73 s, a trained model's best 5.342 s, DeepRacer's real evaluations 16 s. Computed once
per track content and floor version, kept in memory and in the data folder
(`cache/lap-floors`, one small JSON per track, written atomically).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Final

import numpy as np
from shapely.geometry import Polygon

from sim.coach.limits import CarLimits, SpeedLevel
from sim.coach.racing_line import (
    SPACING,
    LineFit,
    LineProblem,
    RoadFrame,
    fit_of,
    optimise_line,
    tightest_turn,
)
from sim.coach.speed_profile import driven_corner_speeds, flying_profile
from sim.foundation.atomic import write_text_atomic
from sim.foundation.home import data_home
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.physics.reference_driver import loop_curvature
from sim.tracks.track import Track

# Bump with any change that moves a floor: cached floors of another version are not read.
FLOOR_FORMAT: Final = 4
SLACK: Final = 0.95
GRIP: Final = 10.0  # m/s^2 sideways
ACCELERATION: Final = 15.0  # m/s^2 speeding up
BRAKING: Final = 20.0  # m/s^2
# The road is widened no further than this share of the centre line's radius on the
# inside of a bend (measured over FOLD_SPAN metres each side), where its normals cross.
FOLD_SHARE: Final = 0.8
FOLD_SPAN: Final = 0.25
# Weights on the line's length (beside its curvature) of the shorter lines also tried.
LENGTH_SEARCH: Final = (0.1, 0.3, 1.0, 3.0, 10.0)


def cutting_reach(car: CarSpec = DEEPRACER_CAR) -> float:
    """Metres the car's centre may be beyond the border while one wheel centre is on it."""
    return float(np.max(np.hypot(*car.wheel_offsets.T)))


def floor_limits(car: CarSpec = DEEPRACER_CAR) -> CarLimits:
    """The able car the floor is the limit lap of (module docstring)."""
    top = car.max_speed * car.speed_gain
    return CarLimits(
        grip=GRIP,
        acceleration=ACCELERATION,
        braking=BRAKING,
        effective_wheelbase=car.wheelbase,
        understeer=0.0,
        steering_lag=0.0,
        levels=(SpeedLevel(top, car.max_steering_deg),),
        continuous=True,
        crawl=car.min_speed * car.speed_gain,
        label="any DeepRacer car",
    )


def widened_frame(track: Track, reach: float) -> RoadFrame:
    """Where the floor's line may go: `reach` beyond each border, along the centre line's
    normals, short of where they cross inside a bend (but never narrower than the road)."""
    s, base, normal = track.resampled(SPACING)
    right, left = track.lateral_extents(s)
    bend = loop_curvature(base, max(1, round(FOLD_SPAN / SPACING)))
    fold = FOLD_SHARE / np.maximum(np.abs(bend), 1e-9)
    high = np.where(bend > 0.0, np.minimum(left + reach, np.maximum(left, fold)), left + reach)
    low = np.where(bend < 0.0, np.maximum(right - reach, np.minimum(right, -fold)), right - reach)
    return RoadFrame(base, normal, low, high)


def compute_floor(track: Track, car: CarSpec = DEEPRACER_CAR) -> float | None:
    """The floor worked out afresh (`lap_floor` caches it); None when the solver found no
    line at all (module docstring)."""
    limits = floor_limits(car)
    frame = widened_frame(track, cutting_reach(car))
    try:
        found = optimise_line(track, limits, frame=frame)
        shorter = _shorter_lines(frame, limits)
    except (ValueError, ArithmeticError):  # numpy's and the solver's: no line either
        return None
    cap = tightest_turn(limits)
    # Where the coach's line turns tighter than even this car can (a hairpin it did not
    # quite open up), the car is let round at its tightest turn's speed, not at a crawl.
    steps = found.profile.steps
    corner = driven_corner_speeds(np.clip(found.curvature[:-1], -cap, cap), steps, limits)
    laps = [flying_profile(corner, steps, limits).lap_seconds]
    laps += [fit.profile.lap_seconds for fit in shorter if _drivable(fit, cap)]
    fastest = min(lap for lap in laps if math.isfinite(lap) and lap > 0.0) if laps else None
    if fastest is None:
        return None
    return max(SLACK * fastest, cut_loop_metres(track, cutting_reach(car)) / limits.top_speed)


def _shorter_lines(frame: RoadFrame, limits: CarLimits) -> list[LineFit]:
    """Lines that weigh length more than the coach tries: an able car is held back by its
    top speed more than by its corners, so the fastest line for it is a shorter one."""
    problem = LineProblem.of(frame)
    flat = np.ones(len(frame.base))
    return [fit_of(frame, problem.solve(flat, weight), limits) for weight in LENGTH_SEARCH]


def _drivable(fit: LineFit, cap: float) -> bool:
    return bool(np.max(np.abs(fit.curvature)) <= cap)


def cut_loop_metres(track: Track, reach: float) -> float:
    """The shortest loop a car's centre can drive round the infield when it may cut
    `reach` into it: the perimeter of the convex hull of the infield less `reach` all
    round (a lap goes round all of that, so no lap is shorter: physics, no search)."""
    borders = [Polygon(track.inner), Polygon(track.outer)]
    infield = min(borders, key=lambda polygon: polygon.area)
    kept = infield.buffer(-reach)
    return float(kept.convex_hull.length) if not kept.is_empty else 0.0


def floor_key(car: CarSpec = DEEPRACER_CAR) -> str:
    """The floor's version: what it is computed with, hashed."""
    shape = (FLOOR_FORMAT, SPACING, SLACK, FOLD_SHARE, FOLD_SPAN, LENGTH_SEARCH)
    text = repr((*shape, cutting_reach(car), floor_limits(car)))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# Floors by (track hash, floor key); None: no line was found, the caller uses the hull.
_known: dict[tuple[str, str], float | None] = {}


def lap_floor(track: Track) -> float | None:
    """Seconds no lap on `track` can beat under DeepRacer's rules, or None when the coach
    found no line for it (module docstring). Cached by the track's content."""
    key = (track.content_hash, floor_key())
    if key not in _known:
        try:
            path: Path | None = _cache_file(*key)
        except OSError:  # no data folder to keep it in: worked out for this process only
            path = None
        cached = None if path is None else _read_cached(path, track.content_hash)
        if cached is None:
            cached = (compute_floor(track),)
            if path is not None:
                _write_cached(path, track.content_hash, cached[0])
        _known[key] = cached[0]
    return _known[key]


def forget_floors() -> None:
    """Empty the in-memory cache (tests; the disk cache is the data folder's)."""
    _known.clear()


def _cache_file(track_hash: str, key: str) -> Path:
    return data_home() / "cache" / "lap-floors" / f"{track_hash[:16]}-{key}.json"


def _write_cached(path: Path, track_hash: str, seconds: float | None) -> None:
    text = json.dumps({"track_hash": track_hash, "floor_seconds": seconds})
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, text)
    except OSError:
        pass  # a cache: the floor is still right, it is computed again next time


def _read_cached(path: Path, track_hash: str) -> tuple[float | None] | None:
    """(floor,) as cached (the floor None when no line was found), or None: no cache."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("track_hash") != track_hash:
        return None
    seconds = data.get("floor_seconds")
    if seconds is None:
        return (None,)
    if isinstance(seconds, bool) or not isinstance(seconds, int | float):
        return None
    if not math.isfinite(seconds) or seconds <= 0.0:
        return None
    return (float(seconds),)

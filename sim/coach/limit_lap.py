"""A track's limit lap: the fastest line a car can drive round it and its speeds, with the
flying and standing lap times, cached by the track's content and the car's limits.

The cache is in memory for the process and on disk in the data folder (`cache/limit-laps`,
one `.npz` of plain arrays per track and car, written atomically and read back without
pickles), so `racer-tui tracks show` answers at once the second time. A cache file that
does not read back as a limit lap of this format is computed again.
"""

from __future__ import annotations

import hashlib
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np

from sim.coach.limits import CarLimits, car_limits
from sim.coach.racing_line import EDGE_MARGIN, SPACING, optimise_line
from sim.coach.speed_profile import driven_corner_speeds, standing_profile
from sim.deepracer.action_space import ActionSpace
from sim.foundation.arrays import FloatArray
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.home import data_home
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.tracks.track import Track

CACHE_FORMAT: Final = 1
_ARRAYS: Final = ("points", "curvature", "speeds", "standing_speeds")


@dataclass(frozen=True, eq=False)
class LimitLap:
    """The fastest lap found for a car on a track (arrays closed: first point repeated)."""

    track_name: str
    track_hash: str
    limits: str  # whose limits: "racer-tui's car", "the action space"
    points: FloatArray  # (n + 1, 2) the line, metres
    curvature: FloatArray  # (n + 1,) 1/m, positive turning left
    speeds: FloatArray  # (n + 1,) m/s on a flying lap
    standing_speeds: FloatArray  # (n + 1,) m/s from rest at the first point

    @property
    def distances(self) -> FloatArray:
        """Metres along the line from its first point to each point."""
        steps = np.hypot(*np.diff(self.points, axis=0).T)
        return np.concatenate([[0.0], np.cumsum(steps)])

    @property
    def flying_seconds(self) -> float:
        return _lap_seconds(self.distances, self.speeds)

    @property
    def standing_seconds(self) -> float:
        return _lap_seconds(self.distances, self.standing_speeds)

    def resampled(self, every: float) -> tuple[FloatArray, FloatArray]:
        """The line every `every` metres (points, flying speeds), the closing point left out:
        what a reward function or a spreadsheet takes."""
        distances = self.distances
        at = np.arange(0.0, distances[-1] - 1e-9, max(every, SPACING))
        points = np.stack([np.interp(at, distances, self.points[:, i]) for i in (0, 1)], axis=1)
        return points, np.interp(at, distances, self.speeds)


def _lap_seconds(distances: FloatArray, speeds: FloatArray) -> float:
    steps = np.diff(distances)
    return float(np.sum(2.0 * steps / np.maximum(speeds[:-1] + speeds[1:], 1e-9)))


_computed: dict[tuple[str, str], LimitLap] = {}


def limit_lap(
    track: Track, car: CarSpec = DEEPRACER_CAR, space: ActionSpace | None = None
) -> LimitLap:
    """The limit lap of `car` on `track`, within `space`'s actions when given."""
    limits = car_limits(car, space)
    key = (track.content_hash, _limits_key(limits, car))
    found = _computed.get(key)
    if found is None:
        found = _read_cached(_cache_file(*key), track, limits)
        if found is None:
            found = compute_limit_lap(track, limits, car)
            _write_cached(_cache_file(*key), found)
        _computed[key] = found
    return found


def compute_limit_lap(track: Track, limits: CarLimits, car: CarSpec) -> LimitLap:
    """The limit lap worked out afresh (`limit_lap` caches it)."""
    fit = optimise_line(track, limits, half_width=car.width / 2.0)
    corner = driven_corner_speeds(fit.curvature[:-1], fit.profile.steps, limits)
    standing = standing_profile(corner, fit.profile.steps, limits)
    return LimitLap(
        track_name=track.name,
        track_hash=track.content_hash,
        limits=limits.label,
        points=fit.points,
        curvature=fit.curvature,
        speeds=fit.profile.speeds,
        standing_speeds=standing.speeds,
    )


def _limits_key(limits: CarLimits, car: CarSpec) -> str:
    text = repr((CACHE_FORMAT, SPACING, EDGE_MARGIN, car.width, limits))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _cache_file(track_hash: str, limits_key: str) -> Path:
    return data_home() / "cache" / "limit-laps" / f"{track_hash[:16]}-{limits_key}.npz"


def _write_cached(path: Path, lap: LimitLap) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, **{name: getattr(lap, name) for name in _ARRAYS})
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, buffer.getvalue())
    except OSError:
        pass  # a cache: the lap is still right, it will be computed again next time


def _read_cached(path: Path, track: Track, limits: CarLimits) -> LimitLap | None:
    try:
        with np.load(path, allow_pickle=False) as stored:
            arrays = {name: np.asarray(stored[name], dtype=np.float64) for name in _ARRAYS}
    except (OSError, KeyError, ValueError):
        return None
    points = arrays["points"]
    n = len(points)
    shaped = points.ndim == 2 and points.shape[1:] == (2,) and n >= 4
    if not shaped or any(arrays[name].shape != (n,) for name in _ARRAYS[1:]):
        return None
    if not all(np.all(np.isfinite(values)) for values in arrays.values()):
        return None
    return LimitLap(
        track_name=track.name,
        track_hash=track.content_hash,
        limits=limits.label,
        points=points,
        curvature=arrays["curvature"],
        speeds=arrays["speeds"],
        standing_speeds=arrays["standing_speeds"],
    )

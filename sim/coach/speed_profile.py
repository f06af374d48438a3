"""The fastest speeds along a closed line under the car's limits, and their lap times.

Each point may go no faster than its corner speed (`CarLimits.corner_speed` of the line's
curvature there); a forward pass limits how fast the speed can rise from one point to the
next (v'^2 = v^2 + 2 a ds), a backward pass how fast it can fall before the next corner.
Both passes are one vectorised scan each: with u = v^2 and K the running sum of 2 a ds,
u_i = K_i + min over j <= i of (C_j - K_j) for the caps C.

- The car's steering answers with a lag, so its path bends later than a line drawn with
  sudden changes of curvature: where the line straightens, the car is still turning. A
  profile for a line the car can follow (`driven_corner_speeds`) takes each point's
  curvature as the larger of the line's and the lagging car's, at the profile's own
  speeds (a few rounds, each from the last).
- Flying lap: the car is already at speed on the line; the profile is the loop's steady
  state (three laps are scanned, the middle one is kept).
- Standing start: from rest at the line's first point, the lap ends back at it; the lap
  after it still constrains how fast the car may cross the line.
Lap time: each step at constant acceleration, dt = 2 ds / (v_i + v_i+1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.coach.limits import CarLimits
from sim.foundation.arrays import FloatArray


@dataclass(frozen=True)
class SpeedProfile:
    """Speeds at the points of a closed line (the first point repeated at the end)."""

    speeds: FloatArray  # (n + 1,) m/s
    steps: FloatArray  # (n,) metres from each point to the next
    lap_seconds: float

    @property
    def times(self) -> FloatArray:
        """Seconds from the line's first point to each point."""
        return np.concatenate([[0.0], np.cumsum(_step_times(self.steps, self.speeds))])


def _step_times(steps: FloatArray, speeds: FloatArray) -> FloatArray:
    return np.asarray(2.0 * steps / np.maximum(speeds[:-1] + speeds[1:], 1e-9))


def _rise_limited(caps: FloatArray, gains: FloatArray) -> FloatArray:
    """u_0 = caps_0, u_i = min(caps_i, u_i-1 + gains_i-1): speeds squared that can rise no
    faster than `gains` allow from one point to the next."""
    climbed = np.concatenate([[0.0], np.cumsum(gains)])
    return np.asarray(climbed + np.minimum.accumulate(caps - climbed))


def _profile(caps: FloatArray, steps: FloatArray, limits: CarLimits) -> FloatArray:
    """Speeds squared within `caps` (one per point, `steps` between them), rising and
    falling within the car's acceleration and braking."""
    forward = _rise_limited(caps, 2.0 * limits.acceleration * steps)
    backward = _rise_limited(forward[::-1], 2.0 * limits.braking * steps[::-1])[::-1]
    return np.asarray(backward)


def flying_profile(corner: FloatArray, steps: FloatArray, limits: CarLimits) -> SpeedProfile:
    """The loop's steady state: `corner` speeds at its n points, `steps` (n,) metres from
    each point to the next (the last back to the first)."""
    n = len(corner)
    caps = np.tile(np.square(corner), 3)
    squared = _profile(caps, np.tile(steps, 3)[:-1], limits)
    speeds = np.sqrt(np.maximum(squared[n : 2 * n + 1], 0.0))
    return SpeedProfile(speeds, steps, float(np.sum(_step_times(steps, speeds))))


def standing_profile(corner: FloatArray, steps: FloatArray, limits: CarLimits) -> SpeedProfile:
    """From rest at the first point, once round to it (the next lap's corners still
    count before the line)."""
    n = len(corner)
    caps = np.tile(np.square(corner), 2)
    caps[0] = 0.0
    squared = _profile(caps, np.tile(steps, 2)[:-1], limits)
    speeds = np.sqrt(np.maximum(squared[: n + 1], 0.0))
    return SpeedProfile(speeds, steps, float(np.sum(_step_times(steps, speeds))))


LAG_ROUNDS = 3


def lagging_curvature(
    curvature: FloatArray, steps: FloatArray, speeds: FloatArray, lag: float
) -> FloatArray:
    """The curvature of a car whose steering follows the line's `curvature` with a lag of
    `lag` seconds, driving at `speeds`: a first-order filter over the distance covered in
    that time, round the loop twice so that it starts settled."""
    n = len(curvature)
    previous = np.roll(steps, 1)  # metres from the point before
    blend = 1.0 - np.exp(-previous / (np.maximum(speeds[:n], 0.3) * max(lag, 1e-6)))
    bend = float(curvature[-1])
    out = np.empty(n)
    line, share = curvature.tolist(), blend.tolist()
    for _ in range(2):
        for i in range(n):
            bend += (line[i] - bend) * share[i]
            out[i] = bend
    return out


def driven_corner_speeds(curvature: FloatArray, steps: FloatArray, limits: CarLimits) -> FloatArray:
    """Corner speeds for a line the car follows with its steering's lag (module
    docstring): at each point, the larger of the line's curvature and the car's."""
    corner = limits.corner_speed(curvature)
    for _ in range(LAG_ROUNDS):
        speeds = flying_profile(corner, steps, limits).speeds
        lagging = lagging_curvature(curvature, steps, speeds, limits.steering_lag)
        corner = limits.corner_speed(np.maximum(np.abs(curvature), np.abs(lagging)))
    return corner

"""A discrete action space made from a track's limit lap: the (steering, speed) pairs the
line asks for, clustered the way the DeepRacer community does it by hand.

Every point of the line asks for one action: the speed to command there (the limit lap's
speed over the motor's gain) and the steering angle that holds the line's curvature at that
speed. The pairs are weighted by the time the car spends at each point, since a policy picks
an action per step, not per metre. A car never drives the line exactly, so each point also
asks, with less weight, for a correction either way; without those a space built for a
left-turning track has no way to steer right back onto it. Weighted k-means then picks
`count` actions, rounded to what the console shows and kept within its ranges.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from sim.coach.limit_lap import limit_lap
from sim.coach.limits import car_limits
from sim.deepracer.action_space import Action, ActionSpace
from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.foundation.arrays import FloatArray
from sim.foundation.remedies import RemedyError
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.tracks.track import Track

MIN_COUNT: Final = 3
MAX_COUNT: Final = 30
# Degrees either side of the line's own angle a car steers to get back onto it, and the share
# of a point's weight each correction gets.
CORRECTION_DEG: Final = 10.0
CORRECTION_WEIGHT: Final = 0.2
_ITERATIONS: Final = 60


class LineActionsError(RemedyError):
    """The count asked for cannot be made; `str()` is one sentence."""


def actions_from_line(track: Track, count: int, car: CarSpec = DEEPRACER_CAR) -> ActionSpace:
    """`count` discrete actions for driving `track`'s limit lap, slowest and leftmost first."""
    if not MIN_COUNT <= count <= MAX_COUNT:
        raise LineActionsError(
            f"the action count must be from {MIN_COUNT} to {MAX_COUNT}, not {count}."
        )
    pairs, weights = _asked_actions(track, car)
    # Distances in k-means compare degrees with m/s: scale both to their console range.
    scale = np.array([MAX_STEERING, MAX_SPEED])
    centres = _weighted_kmeans(pairs / scale, weights, count) * scale
    actions = sorted(
        {
            (
                round(float(np.clip(steer, -MAX_STEERING, MAX_STEERING)), 1),
                round(float(np.clip(speed, MIN_SPEED, MAX_SPEED)), 2),
            )
            for steer, speed in centres
        },
        key=lambda pair: (pair[1], -pair[0]),
    )
    return ActionSpace(kind="discrete", actions=tuple(Action(s, v) for s, v in actions))


def _asked_actions(track: Track, car: CarSpec) -> tuple[FloatArray, FloatArray]:
    """(steering deg, commanded speed) for each point of the line and its corrections, with
    the seconds each stands for."""
    lap = limit_lap(track, car)
    limits = car_limits(car)
    speeds = lap.speeds[:-1]
    curvature = lap.curvature[:-1]
    steps = np.diff(lap.distances)
    seconds = steps / np.maximum(speeds, 1e-6)
    wheelbase = limits.effective_wheelbase * (1.0 + limits.understeer * np.square(speeds))
    steering = np.degrees(np.arctan(curvature * wheelbase))
    commanded = np.clip(speeds / car.speed_gain, MIN_SPEED, MAX_SPEED)
    corrections = [
        np.stack([np.clip(steering + side, -MAX_STEERING, MAX_STEERING), commanded], axis=1)
        for side in (-CORRECTION_DEG, CORRECTION_DEG)
    ]
    pairs = np.concatenate([np.stack([steering, commanded], axis=1), *corrections])
    weights = np.concatenate([seconds, seconds * CORRECTION_WEIGHT, seconds * CORRECTION_WEIGHT])
    return pairs, weights


def _weighted_kmeans(points: FloatArray, weights: FloatArray, count: int) -> FloatArray:
    """Lloyd's k-means with weights, seeded by weighted k-means++ from a fixed seed so the
    same track always gives the same actions."""
    rng = np.random.default_rng(0)
    share = weights / weights.sum()
    centres = [points[rng.choice(len(points), p=share)]]
    for _ in range(1, count):
        nearest = np.min([np.sum((points - c) ** 2, axis=1) for c in centres], axis=0)
        chance = share * nearest
        if chance.sum() <= 0.0:
            break  # fewer distinct asks than actions: every one already has its own
        centres.append(points[rng.choice(len(points), p=chance / chance.sum())])
    grid = np.array(centres)
    for _ in range(_ITERATIONS):
        labels = np.argmin(((points[:, None, :] - grid[None]) ** 2).sum(axis=2), axis=1)
        moved = grid.copy()
        for k in range(len(grid)):
            members = labels == k
            if members.any():
                moved[k] = np.average(points[members], axis=0, weights=weights[members])
        if np.allclose(moved, grid, atol=1e-6):
            break
        grid = moved
    return grid

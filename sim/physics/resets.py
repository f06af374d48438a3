"""Resets: where DeepRacer puts a car back after an off-track, and what it costs.

In an evaluation or a race DeepRacer does not always end a car's run when it leaves the
track: up to `number_of_resets` times it puts the car back and holds it for a penalty while
the clock runs (simapp `bundle/markov/agent_ctrl/rollout_agent_ctrl.py`,
`_check_for_phase_change` and `_judge_action_at_run_phase`). This module is the one place
that knows where the car goes back and what each kind of reset costs by default.

Where it goes back (`_get_car_reset_model_state`, `_get_reset_poses`): at the distance along
the track that the car's look-ahead point had reached one step before it left, on the lane
(half-way between the centre line and a border) nearer to where the car centre was then,
pointing at that lane's next waypoint, standing still.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.remedies import RemedyError
from sim.tracks.geometry import PointProjector
from sim.tracks.track import Track

if TYPE_CHECKING:
    from sim.physics.simulation import TrackSimulation

# simapp's evaluation worker defaults (`bundle/markov/evaluation_worker.py`):
# OFF_TRACK_PENALTY 2.0 s, COLLISION_PENALTY 5.0 s; a reversed car costs the off-track
# penalty unless REVERSE_PENALTY says otherwise; IMMOBILIZED_PENALTY is 0.
OFF_TRACK_PENALTY = 2.0
COLLISION_PENALTY = 5.0
IMMOBILIZED_PENALTY = 0.0
# simapp refuses 1 ("number of resets is less than 2"): one reset is not a useful setting.
MIN_RESETS = 2
MAX_RESETS = 10_000


class ResetRulesError(RemedyError):
    """A reset setting that cannot be used; the message says which and why."""


@dataclass(frozen=True)
class ResetRules:
    """How an evaluation trial treats an off-track, a crash, a reversal or a stop.

    `number_of_resets` is simapp's NUMBER_OF_RESETS: how many of these a trial survives
    (each puts the car back and adds its penalty to the trial's time); the next one ends the
    trial with its status. 0 ends a trial at the first, as DeepRacer's training does.
    """

    number_of_resets: int = 0
    off_track_penalty: float = OFF_TRACK_PENALTY
    collision_penalty: float = COLLISION_PENALTY
    reverse_penalty: float | None = None  # None: the off-track penalty
    immobilized_penalty: float = IMMOBILIZED_PENALTY

    def __post_init__(self) -> None:
        resets = self.number_of_resets
        if isinstance(resets, bool) or not isinstance(resets, int):
            raise ResetRulesError(f"the number of resets must be a whole number, not {resets!r}.")
        if resets != 0 and not MIN_RESETS <= resets <= MAX_RESETS:
            raise ResetRulesError(
                f"the number of resets must be 0 or from {MIN_RESETS} to {MAX_RESETS}, "
                f"not {resets}."
            )
        for name in ("off_track_penalty", "collision_penalty", "immobilized_penalty"):
            _check_seconds(name, getattr(self, name))
        if self.reverse_penalty is not None:
            _check_seconds("reverse_penalty", self.reverse_penalty)

    def penalty(self, status: str) -> float:
        """Seconds a reset for `status` costs."""
        if status == EpisodeStatus.OFF_TRACK:
            return self.off_track_penalty
        if status == EpisodeStatus.CRASHED:
            return self.collision_penalty
        if status == EpisodeStatus.REVERSED:
            return self.off_track_penalty if self.reverse_penalty is None else self.reverse_penalty
        if status == EpisodeStatus.IMMOBILIZED:
            return self.immobilized_penalty
        return 0.0


def _check_seconds(name: str, value: float) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ResetRulesError(f"{name} must be a number of seconds, not {value!r}.")
    if not (math.isfinite(value) and 0.0 <= value <= 60.0):
        raise ResetRulesError(f"{name} must be between 0 and 60 seconds, not {value!r}.")


# Statuses a reset can follow; anything else (a lap, time up) ends a trial.
RESETTABLE = frozenset(
    {
        EpisodeStatus.OFF_TRACK,
        EpisodeStatus.CRASHED,
        EpisodeStatus.REVERSED,
        EpisodeStatus.IMMOBILIZED,
    }
)


@dataclass(frozen=True)
class _Lanes:
    centre: PointProjector
    inner: PointProjector
    outer: PointProjector


_LANES: weakref.WeakKeyDictionary[Track, _Lanes] = weakref.WeakKeyDictionary()


def _lanes(track: Track) -> _Lanes:
    found = _LANES.get(track)
    if found is None:
        found = _LANES[track] = _Lanes(
            PointProjector.of(track.centerline),
            PointProjector(track.inner_lane),
            PointProjector(track.outer_lane),
        )
    return found


def reset_pose(track: Track, s: float, car_x: float, car_y: float) -> tuple[float, float, float]:
    """(x, y, yaw) of a car put back at arc length `s` along `track`'s centre line.

    `s` is where the look-ahead point was a step before the car left; (`car_x`, `car_y`) is
    where the car centre was then, which picks the nearer lane.
    """
    lanes = _lanes(track)
    cx, cy = lanes.centre.point_at(s)
    best: tuple[float, float, float] | None = None
    best_distance = math.inf
    for lane in (lanes.inner, lanes.outer):
        seg, t, x, y = lane.project(cx, cy)
        distance = math.hypot(x - car_x, y - car_y)
        if distance < best_distance:
            # Towards the lane's next waypoint (simapp's forward difference); on a waypoint,
            # the one after it.
            nx, ny = _end(lane, (seg + 1) % len(lane.starts) if t >= 1.0 else seg)
            yaw = math.atan2(ny - y, nx - x)
            best, best_distance = (x, y, yaw), distance
    assert best is not None
    return best


def _end(lane: PointProjector, seg: int) -> tuple[float, float]:
    (sx, sy), (vx, vy) = lane.starts[seg], lane.vectors[seg]
    return sx + vx, sy + vy


def put_back(
    sim: TrackSimulation,
    car: int,
    *,
    s_ahead: float,
    car_x: float,
    car_y: float,
    travelled: float,
    pose: tuple[float, float, float] | None = None,
) -> None:
    """Put `car` back where DeepRacer would (`reset_pose`, from where its look-ahead point,
    `s_ahead`, and its centre were a step before it left), or at `pose`; its progress
    (`travelled` a step before) follows it, standing still."""
    x, y, yaw = pose if pose is not None else reset_pose(sim.track, s_ahead, car_x, car_y)
    sim.put(car, x, y, yaw, 0.0)
    length = sim.track.length
    moved = (float(sim.s[car]) - s_ahead + length / 2.0) % length - length / 2.0
    sim.continue_episode(car, travelled + moved)

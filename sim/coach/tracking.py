"""The simulator driven along a line at its planned speeds: proof that a limit lap can be
driven, and how close the driving comes to the plan.

The follower chooses each step's steering by trying them all on copies of the car (a small
predictive controller on the simulator's own physics), and commands the planned speed a
little ahead, over the motor's gain, which the car settles at. It starts at rest on the
line's first point; the first lap is the standing lap, the second the flying one, both
timed as races time them (the simulator's progress, inside the step that crosses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.arrays import FloatArray
from sim.physics.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec, Fleet
from sim.physics.simulation import TrackSimulation
from sim.tracks.geometry import PointProjector, PolylineProjector
from sim.tracks.track import Track

# Steering angles tried each step (0.5 degree apart) and control steps they are tried over.
CANDIDATES = 121
HORIZON = 6
# Square metres of cost per square degree of change from the last step's angle.
_CHANGE_WEIGHT = 1e-7
# Control steps of the plan the speed command looks ahead, besides the motor's lag.
_SPEED_LEAD_STEPS = 0.5


@dataclass(frozen=True)
class DrivenLaps:
    """What the simulator made of a line: the standing lap and the flying lap after it,
    seconds (nan if it did not get round), and how it ended."""

    standing: float
    flying: float
    status: str
    off_line: float = math.nan  # metres: the car centre's mean distance from the line, laps 1-2

    @property
    def completed(self) -> bool:
        return math.isfinite(self.flying)


class LineFollower:
    """Steers one car along `points` (closed, (n + 1, 2)) at `speeds` (m/s, as driven),
    `curvature` (1/m, signed) at each point.

    The steering is chosen by trying every angle on copies of the car (a fleet of
    `CANDIDATES` cars in the car's own state, `HORIZON` control steps ahead, each holding
    one angle) and keeping the one that stays closest to the line: the steering's lag and
    the car's grip are then the simulator's own, not a model of them. The speed is the
    plan's where the car will be once the motor has answered (a command holds for a whole
    step), or the lowest ahead when the plan brakes."""

    def __init__(
        self, points: FloatArray, speeds: FloatArray, curvature: FloatArray, car: CarSpec
    ) -> None:
        self.car = car
        projector = PolylineProjector(points)
        self.line = PointProjector.of(projector, lazy=True)
        self._projector = projector
        self.speeds = speeds
        self.curvature = curvature
        self._probe = Fleet(CANDIDATES, car)
        self._angles = np.linspace(-car.max_steering_deg, car.max_steering_deg, CANDIDATES)
        self._last = 0.0

    def act(self, sim: TrackSimulation) -> tuple[float, float]:
        """(steering degrees, commanded speed m/s) for car 0."""
        speed_command = self._speed_command(sim)
        steering = self._steering(sim, speed_command)
        self._last = steering
        return steering, speed_command

    def _speed_command(self, sim: TrackSimulation) -> float:
        car, line = self.car, self.line
        speed = max(float(sim.fleet.speed[0]), 0.3)
        segment, t, _, _ = line.project(float(sim.fleet.x[0]), float(sim.fleet.y[0]))
        here = line.arc_length(segment, t)
        lead = _SPEED_LEAD_STEPS * STEP_SECONDS + car.speed_time_constant
        ahead = (here + speed * np.linspace(0.0, lead, 4)) % line.total_length
        plan = np.interp(ahead, line.cumulative, self.speeds)
        wanted = float(plan[-1]) if plan[-1] >= plan[0] else float(plan.min())
        return wanted / car.speed_gain

    def _steering(self, sim: TrackSimulation, speed_command: float) -> float:
        """The candidate angle whose copies stay closest to the line over the horizon (a
        little weight on change, so that equal choices do not flicker)."""
        real, probe = sim.fleet, self._probe
        probe.copy_car(real, 0)
        speeds = np.full(CANDIDATES, speed_command)
        probe.set_targets(self._angles, speeds)
        cost = _CHANGE_WEIGHT * np.square(self._angles - self._last)
        for step in range(HORIZON):
            probe.step()
            xy = np.stack([probe.x, probe.y], axis=1)
            segment, t, foot = self._projector.project(xy)
            cost += np.sum(np.square(xy - foot), axis=1)
            if step + 1 < HORIZON:
                # After the first step each copy steers as the line bends where it is: the
                # choice is this step's angle, not one angle held for the whole horizon.
                here = self._projector.arc_length(segment, t)
                bend = np.interp(here, self.line.cumulative, self.curvature)
                angles = np.degrees(self.car.steering_for(bend, np.maximum(probe.speed, 0.3)))
                probe.set_targets(angles, speeds)
        return float(self._angles[int(np.argmin(cost))])


def drive_line(
    track: Track,
    points: FloatArray,
    speeds: FloatArray,
    curvature: FloatArray,
    *,
    car: CarSpec = DEEPRACER_CAR,
    max_seconds: float = 300.0,
) -> DrivenLaps:
    """Drive two laps along the line from rest at its first point (module docstring)."""
    sim = TrackSimulation(track, 1, car=car, lookup_grids=False)
    sim.reset_car(0, start_s=0.0)
    start, toward = points[0], points[1] - points[0]
    sim.put(0, float(start[0]), float(start[1]), math.atan2(toward[1], toward[0]))
    follower = LineFollower(points, speeds, curvature, car)
    laps: list[float] = []
    before = float(sim.travelled[0])
    lap_started = 0.0
    off: list[float] = []
    for step in range(int(max_seconds * STEP_HZ)):
        steering, speed = follower.act(sim)
        sim.apply(np.array([steering]), np.array([speed]))
        x, y = float(sim.fleet.x[0]), float(sim.fleet.y[0])
        _, _, foot_x, foot_y = follower.line.project(x, y)
        off.append(math.hypot(x - foot_x, y - foot_y))
        status = sim.status[0]
        after = float(sim.travelled[0])
        if status == EpisodeStatus.LAP_COMPLETE:
            # The crossing inside the step, as races time their laps.
            fraction = (track.length - before) / max(after - before, 1e-9)
            crossed = (step + min(max(fraction, 0.0), 1.0)) * STEP_SECONDS
            laps.append(crossed - lap_started)
            if len(laps) == 2:
                return DrivenLaps(laps[0], laps[1], str(status), float(np.mean(off)))
            lap_started = crossed
            sim.continue_episode(0, after - track.length)
            after -= track.length
        elif status != EpisodeStatus.IN_PROGRESS:
            return _unfinished(laps, str(status))
        before = after
    return _unfinished(laps, str(EpisodeStatus.TIME_UP))


def _unfinished(laps: list[float], status: str) -> DrivenLaps:
    standing = laps[0] if laps else math.nan
    return DrivenLaps(standing, math.nan, status)

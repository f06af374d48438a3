"""The simulator driven along a line at its planned speeds: proof that a limit lap can be
driven, and how close the driving comes to the plan.

The follower is the reference driver's kind of controller, aimed at a given line: pure
pursuit on the line from where the car will be once its steering has answered, the angle
from the car's calibrated steering response, and the planned speed read a little ahead
(commanded over the motor's gain, which the car settles at). It starts at rest on the
line's first point; the first lap is the standing lap, the second the flying one, both
timed as races time them (the simulator's progress, inside the step that crosses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec
from sim.geometry import FloatArray, PointProjector, PolylineProjector
from sim.simulation import EpisodeStatus, TrackSimulation
from sim.track import Track

# How quickly the car is brought back onto the line: over about this distance (metres),
# longer at speed.
_REACH_BASE = 0.45
_REACH_PER_SPEED = 0.2  # seconds
_SPEED_AHEAD = (0.0, 0.05, 0.1, 0.15)  # seconds of the plan the speed command looks at


@dataclass(frozen=True)
class DrivenLaps:
    """What the simulator made of a line: the standing lap and the flying lap after it,
    seconds (nan if it did not get round), and how it ended."""

    standing: float
    flying: float
    status: str

    @property
    def completed(self) -> bool:
        return math.isfinite(self.flying)


class LineFollower:
    """Steers one car along `points` (closed, (n + 1, 2)) at `speeds` (m/s, as driven),
    `curvature` (1/m, signed) at each point."""

    def __init__(
        self, points: FloatArray, speeds: FloatArray, curvature: FloatArray, car: CarSpec
    ) -> None:
        self.car = car
        self.line = PointProjector.of(PolylineProjector(points), lazy=True)
        self.speeds = speeds
        self.curvature = curvature

    def act(self, sim: TrackSimulation) -> tuple[float, float]:
        """(steering degrees, commanded speed m/s) for car 0: the line's own curvature
        where the car will be once its steering has answered, less what brings it back
        onto the line (its distance off it and its heading across it)."""
        fleet, car, line = sim.fleet, self.car, self.line
        lead = car.steering_time_constant
        speed, yaw_rate = float(fleet.speed[0]), float(fleet.yaw_rate[0])
        yaw = float(fleet.yaw[0])
        middle = yaw + yaw_rate * 0.5 * lead
        x = float(fleet.x[0]) + speed * lead * math.cos(middle)
        y = float(fleet.y[0]) + speed * lead * math.sin(middle)
        yaw += yaw_rate * lead
        segment, t, foot_x, foot_y = line.project(x, y)
        here = line.arc_length(segment, t)
        along_x, along_y = line.direction_at(here)
        off = -(x - foot_x) * along_y + (y - foot_y) * along_x  # left of the line: positive
        across = math.atan2(math.sin(yaw), math.cos(yaw)) - math.atan2(along_y, along_x)
        across = math.atan2(math.sin(across), math.cos(across))
        reach = _REACH_BASE + _REACH_PER_SPEED * max(speed, 0.3)
        bend = float(np.interp(here, line.cumulative, self.curvature))
        wanted = bend - 2.0 * math.sin(across) / reach - off / reach**2
        steering = float(np.degrees(car.steering_for(wanted, max(speed, 0.3))))
        total = line.total_length
        ahead = [(here + speed * seconds) % total for seconds in _SPEED_AHEAD]
        planned = float(np.min(np.interp(ahead, line.cumulative, self.speeds)))
        limit = car.max_steering_deg
        return min(max(steering, -limit), limit), planned / car.speed_gain


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
    for step in range(int(max_seconds * STEP_HZ)):
        steering, speed = follower.act(sim)
        sim.apply(np.array([steering]), np.array([speed]))
        status = sim.status[0]
        after = float(sim.travelled[0])
        if status == EpisodeStatus.LAP_COMPLETE:
            # The crossing inside the step, as races time their laps.
            fraction = (track.length - before) / max(after - before, 1e-9)
            crossed = (step + min(max(fraction, 0.0), 1.0)) * STEP_SECONDS
            laps.append(crossed - lap_started)
            if len(laps) == 2:
                return DrivenLaps(laps[0], laps[1], str(status))
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

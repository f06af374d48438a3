"""The reference driver: no learning, a racing line driven at the car's grip limit.

Its lap time on a track is the "reference lap" that trained models are compared with, and
it lets a new racer watch a race before training anything.

1. Racing line: a minimum-curvature line inside the road (minus a safety margin), found by
   iterating the bi-Laplacian smoothing step on lateral offsets from the centre line.
2. Speed profile: v = sqrt(grip * margin / curvature), then a forward pass limits
   acceleration and a backward pass limits braking.
3. Control: pure pursuit on the racing line from where the car will be once its steering
   has answered (one steering time constant ahead), turned into a steering angle by the
   car's calibrated steering response; speed target read a little ahead so the motor's
   lag is covered.

Its line is its own, not the coach's minimum-time line (`sim.coach.racing_line`, the limit
lap): reference laps are recorded in races and replayed to verify them, so this line stays
as it was planned, and the coach's may improve without changing a single recorded lap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.arrays import FloatArray
from sim.physics.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec
from sim.physics.simulation import TrackSimulation
from sim.tracks.geometry import PolylineProjector
from sim.tracks.track import Track

_SPACING = 0.05  # racing-line resolution, metres
_EDGE_MARGIN = 0.13  # keep the car centre this far inside the border lines
GRIP_USE = 0.92  # fraction of the grip limit the speed profile plans for
_SMOOTHING_ITERATIONS = 4000


@dataclass(frozen=True)
class RacingLine:
    """A closed line through the track with a planned speed at every point."""

    points: FloatArray  # (M+1, 2), closed
    speeds: FloatArray  # (M+1,) m/s
    curvature: FloatArray  # (M+1,) 1/m, signed (positive = turning left)

    def planned_lap_time(self) -> float:
        seg = np.hypot(*np.diff(self.points, axis=0).T)
        mean_speed = 0.5 * (self.speeds[:-1] + self.speeds[1:])
        return float(np.sum(seg / mean_speed))


def loop_curvature(points: FloatArray, span: int) -> FloatArray:
    """Signed curvature of a closed point loop (without its closing point), via circumcircles."""
    prev_p = np.roll(points, span, axis=0)
    next_p = np.roll(points, -span, axis=0)
    a = np.hypot(*(points - prev_p).T)
    b = np.hypot(*(next_p - points).T)
    c = np.hypot(*(next_p - prev_p).T)
    cross = (points[:, 0] - prev_p[:, 0]) * (next_p[:, 1] - points[:, 1]) - (
        points[:, 1] - prev_p[:, 1]
    ) * (next_p[:, 0] - points[:, 0])
    return np.asarray(2.0 * cross / np.maximum(a * b * c, 1e-12), dtype=np.float64)


def plan_racing_line(track: Track, car: CarSpec = DEEPRACER_CAR) -> RacingLine:
    s, base, normal = track.resampled(_SPACING)
    count = len(s)
    right, left = track.lateral_extents(s)
    low = np.minimum(right + _EDGE_MARGIN, 0.0)
    high = np.maximum(left - _EDGE_MARGIN, 0.0)

    offset = np.zeros(count)
    # The loop's points with two of the other end's on each side: neighbours are slices of
    # one buffer instead of four rolled copies per iteration (the same numbers, faster).
    ring = np.empty((count + 4, 2))
    pts = ring[2:-2]
    for _ in range(_SMOOTHING_ITERATIONS):
        np.multiply(offset[:, None], normal, out=pts)
        pts += base
        ring[:2], ring[-2:] = pts[-2:], pts[:2]
        # Bi-Laplacian step: minimises the summed squared second difference (curvature).
        target = (4.0 * (ring[1:-3] + ring[3:-1]) - (ring[:-4] + ring[4:])) / 6.0
        offset += 0.5 * np.einsum("ij,ij->i", target - pts, normal)
        np.clip(offset, low, high, out=offset)
    points = base + offset[:, None] * normal

    span = max(1, round(0.15 / _SPACING))
    curvature = loop_curvature(points, span)
    speeds = speed_profile(points, curvature, car)
    closed = np.vstack([points, points[:1]])
    return RacingLine(
        points=closed,
        speeds=np.append(speeds, speeds[0]),
        curvature=np.append(curvature, curvature[0]),
    )


def speed_profile(points: FloatArray, curvature: FloatArray, car: CarSpec) -> FloatArray:
    grip = car.grip * GRIP_USE
    limit = np.minimum(car.max_speed, np.sqrt(grip / np.maximum(np.abs(curvature), 1e-6)))
    step = np.hypot(*(np.roll(points, -1, axis=0) - points).T)
    speeds = limit.copy()
    n = len(speeds)
    # Two laps of each pass so the limits carry across the start/finish line.
    for _ in range(2):
        for i in range(n):
            prev = (i - 1) % n
            reachable = math.sqrt(speeds[prev] ** 2 + 2.0 * car.max_acceleration * 0.8 * step[prev])
            speeds[i] = min(speeds[i], reachable)
    for _ in range(2):
        for i in range(n - 1, -1, -1):
            nxt = (i + 1) % n
            stoppable = math.sqrt(speeds[nxt] ** 2 + 2.0 * car.max_braking * 0.8 * step[i])
            speeds[i] = min(speeds[i], stoppable)
    return np.maximum(speeds, car.min_speed)


# Keyed by content, not object: the same track loaded twice plans its line once.
_lines: dict[tuple[str, CarSpec], RacingLine] = {}


def racing_line_for(track: Track, car: CarSpec = DEEPRACER_CAR) -> RacingLine:
    key = (track.content_hash, car)
    if key not in _lines:
        _lines[key] = plan_racing_line(track, car)
    return _lines[key]


class ReferenceDriver:
    """Drives any number of cars of a `TrackSimulation` along the racing line."""

    def __init__(self, track: Track, car: CarSpec = DEEPRACER_CAR) -> None:
        self.track = track
        self.car = car
        self.line = racing_line_for(track, car)
        self.line_projector = PolylineProjector(self.line.points)

    def act(self, sim: TrackSimulation) -> tuple[FloatArray, FloatArray]:
        """(steering degrees, target speed m/s) for every car of `sim`."""
        fleet = sim.fleet
        # The steering answers with a lag: steer from where the car will be by then, on
        # its present arc (without this the car weaves and runs wide on tight tracks).
        lead = self.car.steering_time_constant
        yaw = fleet.yaw + fleet.yaw_rate * lead
        travel = fleet.speed * lead
        middle = fleet.yaw + fleet.yaw_rate * (0.5 * lead)
        x, y = fleet.x + travel * np.cos(middle), fleet.y + travel * np.sin(middle)
        cos_yaw, sin_yaw = np.cos(yaw), np.sin(yaw)
        half_base = self.car.wheelbase / 2.0
        rear_x, rear_y = x - half_base * cos_yaw, y - half_base * sin_yaw
        position = np.stack([x, y], axis=1)
        seg, t, _ = self.line_projector.project(position)
        s_here = self.line_projector.arc_length(seg, t)
        speed = np.maximum(fleet.speed, 0.3)
        look = 0.25 + 0.12 * speed
        target = self.line_projector.point_at(s_here + look)
        dx, dy = target[:, 0] - rear_x, target[:, 1] - rear_y
        local_x = dx * cos_yaw + dy * sin_yaw
        local_y = -dx * sin_yaw + dy * cos_yaw
        distance = np.maximum(np.hypot(local_x, local_y), 1e-6)
        alpha = np.arctan2(local_y, local_x)
        # Pure pursuit gives the curvature that reaches the target; the car's calibrated
        # steering response (not its wheel geometry) turns that into an angle.
        wanted = 2.0 * np.sin(alpha) / distance
        steering = np.degrees(self.car.steering_for(wanted, speed))
        # Plan speed for where the car will be once the motor has responded.
        horizon = s_here[:, None] + speed[:, None] * np.linspace(0.0, 0.35, 6)[None, :]
        planned = np.interp(
            np.mod(horizon, self.line_projector.total_length),
            self.line_projector.cumulative,
            self.line.speeds,
        ).min(axis=1)
        # Off the line, the turn back may be tighter than the plan's: no faster than the
        # grip allows for it.
        planned = np.minimum(
            planned, np.sqrt(self.car.grip * GRIP_USE / np.maximum(np.abs(wanted), 1e-6))
        )
        limit = self.car.max_steering_deg
        return np.clip(steering, -limit, limit), planned


@dataclass(frozen=True)
class ReferenceLap:
    """The reference driver's lap on a track, timed like a DeepRacer evaluation trial."""

    track: str
    lap_time: float  # standing start at the start line, seconds; nan if it did not finish
    status: str
    planned_time: float  # what the speed profile promises for a flying lap
    # Where the car was after each step, from the start up to the step that finished the
    # lap (the line as driven: the controller cuts inside the planned line in corners).
    path: FloatArray = field(default_factory=lambda: np.zeros((0, 2)), compare=False, repr=False)

    @property
    def completed(self) -> bool:
        return self.status == EpisodeStatus.LAP_COMPLETE


def reference_lap(
    track: Track, car: CarSpec = DEEPRACER_CAR, max_seconds: float = 120.0
) -> ReferenceLap:
    """Drive one lap from a standing start at waypoint 0 and time it to the sub-step."""
    sim = TrackSimulation(track, 1, car=car, lookup_grids=False)  # one lap: no grids yet
    driver = ReferenceDriver(track, car)
    sim.reset_car(0, start_s=0.0)
    previous_progress = 0.0
    path = [(float(sim.fleet.x[0]), float(sim.fleet.y[0]))]
    planned = driver.line.planned_lap_time()
    for _ in range(int(max_seconds * STEP_HZ)):
        steering, speed = driver.act(sim)
        sim.apply(steering, speed)
        status = sim.status[0]
        progress = float(sim.travelled[0] / track.length * 100.0)  # unclipped, for interpolation
        if status == EpisodeStatus.LAP_COMPLETE:
            # Interpolate inside the last step so lap times are not quantised to 1/15 s.
            fraction = (100.0 - previous_progress) / max(progress - previous_progress, 1e-9)
            elapsed = (int(sim.steps[0]) - 1 + min(max(fraction, 0.0), 1.0)) * STEP_SECONDS
            return ReferenceLap(track.name, elapsed, str(status), planned, np.array(path))
        if status != EpisodeStatus.IN_PROGRESS:
            return ReferenceLap(track.name, float("nan"), str(status), planned, np.array(path))
        path.append((float(sim.fleet.x[0]), float(sim.fleet.y[0])))
        previous_progress = progress
    return ReferenceLap(
        track.name, float("nan"), str(EpisodeStatus.TIME_UP), planned, np.array(path)
    )

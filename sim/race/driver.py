"""What drives a car in a race or an evaluation: the `Driver` protocol and the reference driver.

A driver sees the whole `TrackSimulation` (so it can build whatever observation its model
needs) and returns one action per car. Races use one car; evaluations may use several.
Nothing here imports torch: policy drivers live in `sim.training.policy` and satisfy the
same protocol.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.physics.reference_driver import GRIP_USE, ReferenceDriver
from sim.physics.simulation import TrackSimulation
from sim.tracks.geometry import PointProjector
from sim.tracks.track import Track

REFERENCE_NAME = "reference"


@dataclass(frozen=True)
class DriverAction:
    """One step's commands for every car of a simulation (arrays of length N)."""

    steering_deg: NDArray[np.float64]  # target steering, degrees, positive = left
    speed: NDArray[np.float64]  # target speed, m/s
    action_index: NDArray[np.int64]  # index into a discrete action space; -1 if continuous


class Driver(Protocol):
    """Anything that can drive: the reference driver, or a trained policy.

    `name` is the model name (or "reference"); `content_hash` identifies the exact car
    (weights and metadata, or "reference:<track hash>"), so results say what raced.
    """

    @property
    def name(self) -> str: ...

    @property
    def content_hash(self) -> str: ...

    def reset(self, sim: TrackSimulation) -> None:
        """Called when a race or trial starts on `sim` (clear any frame stacks, caches)."""

    def act(self, sim: TrackSimulation) -> DriverAction:
        """One action per car in `sim`, for the state it is in now."""
        ...


def driver_under(driver: Driver, runtime: str) -> Driver | None:
    """`driver` as it drove a race recorded under the policy runtime named `runtime`
    (`sim.training.runtimes`: a policy can drive under each version this machine has), or
    None when it cannot drive so here. A driver that drives one way only is itself when
    that way is the runtime."""
    under = getattr(driver, "under", None)
    if callable(under):
        found: Driver | None = under(runtime)
        return found
    return driver if getattr(driver, "runtime", "") == runtime else None


class ReferenceRaceDriver:
    """The no-learning reference driver (racing line at the grip limit) as a `Driver`.

    Its actions are continuous (action index -1). It keeps no state between steps, so
    `reset` has nothing to clear. For a single car (a race) it runs the reference driver's
    control law in plain floats: numpy's per-call overhead on length-1 arrays would cost
    more than everything else in a race step.
    """

    def __init__(self, track: Track, car: CarSpec = DEEPRACER_CAR) -> None:
        self._driver = ReferenceDriver(track, car)
        self.name = REFERENCE_NAME
        self.content_hash = f"{REFERENCE_NAME}:{track.content_hash}"
        self._car = car
        # The reference driver's own racing-line projector, queried one point at a time.
        self._line = PointProjector.of(self._driver.line_projector)
        self._line_speeds: list[float] = self._driver.line.speeds.tolist()

    def reset(self, sim: TrackSimulation) -> None:
        del sim  # stateless

    def act(self, sim: TrackSimulation) -> DriverAction:
        if sim.n == 1 or sim.objects is not None:
            # One car, or cars among objects (trials): car by car, each round its objects.
            pairs = [self._act_one(sim, car) for car in range(sim.n)]
            steering = np.array([pair[0] for pair in pairs])
            speed = np.array([pair[1] for pair in pairs])
        else:
            steering, speed = self._driver.act(sim)
        return DriverAction(
            steering_deg=np.asarray(steering, dtype=np.float64),
            speed=np.asarray(speed, dtype=np.float64),
            action_index=np.full(sim.n, -1, dtype=np.int64),
        )

    def _act_one(self, sim: TrackSimulation, index: int = 0) -> tuple[float, float]:
        """`ReferenceDriver.act` for car `index`: pure pursuit on the racing line from where
        the steering's lag will have taken the car, speed planned for where the car will be
        once the motor has responded (same formulas), and round its objects."""
        fleet = sim.fleet
        car, line = self._car, self._line
        lead = car.steering_time_constant
        speed_now, yaw_rate = float(fleet.speed[index]), float(fleet.yaw_rate[index])
        yaw_now = float(fleet.yaw[index])
        middle = yaw_now + yaw_rate * (0.5 * lead)
        x = float(fleet.x[index]) + speed_now * lead * math.cos(middle)
        y = float(fleet.y[index]) + speed_now * lead * math.sin(middle)
        yaw = yaw_now + yaw_rate * lead
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        half_base = car.wheelbase / 2.0
        rear_x, rear_y = x - half_base * cos_yaw, y - half_base * sin_yaw
        seg, t, _, _ = line.project(x, y)
        s_here = line.arc_length(seg, t)
        speed = max(speed_now, 0.3)
        reach = 0.25 + 0.12 * speed
        target_x, target_y = line.point_at(s_here + reach)
        avoid = None if sim.objects is None else _way_round(sim, reach, speed, index)
        if avoid is not None:
            target_x, target_y, slow_to = avoid
        dx, dy = target_x - rear_x, target_y - rear_y
        local_x = dx * cos_yaw + dy * sin_yaw
        local_y = -dx * sin_yaw + dy * cos_yaw
        distance = max(math.hypot(local_x, local_y), 1e-6)
        alpha = math.atan2(local_y, local_x)
        wanted = 2.0 * math.sin(alpha) / distance
        turning = car.effective_wheelbase * (1.0 + car.understeer * speed * speed)
        # car.steering_for, in floats
        steering = math.degrees(math.atan(wanted * turning)) - car.steering_offset_deg
        total = line.total_length
        planned = min(
            _interp(line.cumulative, self._line_speeds, (s_here + speed * ahead) % total)
            for ahead in _HORIZON
        )
        planned = min(planned, math.sqrt(car.grip * GRIP_USE / max(abs(wanted), 1e-6)))
        if avoid is not None:
            planned = min(planned, slow_to)
        limit = car.max_steering_deg
        return min(max(steering, -limit), limit), planned


# How the reference driver gets round a race's boxes and bot cars: it looks this far ahead
# along the centre line (metres, plus a second's driving), and passes an object with this
# much between its centre and the object's (its half-width, the object's crash half-width
# and a margin), keeping its own centre this far inside the borders.
_LOOK_FOR_OBJECTS = 1.0
_PASS_CLEARANCE = 0.42
_BORDER_MARGIN = 0.13
# Until it is this far past an object it keeps out of its way.
_PAST_OBJECT = 0.45
# Passing, it drives no faster than this (m/s): the swerve needs the grip.
_PASSING_SPEED = 2.2


def _way_round(
    sim: TrackSimulation, reach: float, speed: float, car: int = 0
) -> tuple[float, float, float] | None:
    """Where to aim (x, y) and how fast to go at most while getting round the nearest of
    `car`'s objects ahead, or None when none is in the way: a target `reach` metres on along
    the centre line, beside it on the other side of the object, far enough to clear it. A
    bot car it cannot pass in time it follows at the bot's speed. (Races and trials drive
    the track's way round: objects' distances are along its rows.)"""
    field = sim.objects
    assert field is not None
    length = field.length
    s_car = float(sim.s[car])
    horizon = _LOOK_FOR_OBJECTS + speed
    nearest, nearest_gap = -1, math.inf
    for i, d in enumerate(field.distance[car].tolist()):
        gap = (d - s_car + length / 2.0) % length - length / 2.0
        if -_PAST_OBJECT < gap < horizon and gap < nearest_gap:
            nearest, nearest_gap = i, gap
    if nearest < 0:
        return None
    side = 1.0 if field.left[car, nearest] else -1.0
    offset = side * float(field.from_centre[car, nearest])
    width = float(sim.track_width[car])
    room = width / 2.0 - _BORDER_MARGIN
    # The side with more road: away from the object's side of the centre line.
    wanted = offset - side * _PASS_CLEARANCE
    wanted = min(max(wanted, -room), room)
    centre = sim.centre_projector
    at = s_car + reach
    cx, cy = centre.point_at(at)
    tx, ty = centre.direction_at(at)
    slow_to = _PASSING_SPEED
    if field.reported_speed > 0.0 and abs(wanted - offset) < _PASS_CLEARANCE - 0.05:
        slow_to = field.reported_speed  # no room to pass: follow it
    return cx - ty * wanted, cy + tx * wanted, slow_to


# The reference driver plans speed over these seconds ahead (np.linspace(0, 0.35, 6)).
_HORIZON: tuple[float, ...] = tuple(np.linspace(0.0, 0.35, 6).tolist())


def _interp(xp: list[float], fp: list[float], x: float) -> float:
    """`np.interp` for one point inside an increasing `xp`, with the same arithmetic."""
    if x <= xp[0]:
        return fp[0]
    if x >= xp[-1]:
        return fp[-1]
    j = bisect.bisect_right(xp, x) - 1
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + fp[j]


def reference_driver(track: Track, car: CarSpec = DEEPRACER_CAR) -> Driver:
    """The reference driver for `track` (plans its racing line once per track content)."""
    return ReferenceRaceDriver(track, car)

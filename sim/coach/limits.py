"""What the simulated car can do, as a limit lap needs it: the fastest steady speed for each
curvature, and how quickly the speed can change.

The numbers are the simulator's own (`sim.physics.car.CarSpec`): the tyres hold at most `grip`
m/s^2 sideways; the steering turns no tighter than its largest angle allows at each speed
(curvature = tan(angle) / (effective wheelbase x (1 + understeer x v^2))); the motor
accelerates and brakes at its limits and settles at `speed_gain` times the commanded
speed. A model's action space narrows them: its top speed, its largest steering angle, and
for a discrete space only the speeds it has (each with the largest angle it pairs with
that speed: a car holds a curve between two of its angles by alternating them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.deepracer.action_space import ActionSpace
from sim.foundation.arrays import FloatArray
from sim.physics.car import DEEPRACER_CAR, CarSpec


@dataclass(frozen=True)
class SpeedLevel:
    """A speed the car can hold, and the largest steering angle it can hold it with."""

    speed: float  # m/s, as driven (the commanded speed times the motor's gain)
    steering_deg: float


@dataclass(frozen=True)
class CarLimits:
    grip: float  # m/s^2 sideways
    acceleration: float  # m/s^2
    braking: float  # m/s^2
    effective_wheelbase: float
    understeer: float
    # Seconds the car's path curvature takes to follow its steering (the lag of the part
    # of a command the wheels do not take at once): a line that bends faster than this
    # is driven wider than it is drawn.
    steering_lag: float
    # The speeds the car can hold, slowest first: one for a continuous range (any speed up
    # to it), one per speed for a discrete space.
    levels: tuple[SpeedLevel, ...]
    continuous: bool
    crawl: float  # m/s: the slowest the car drives, where the line asks more than it has
    label: str  # what the limits are of, for people: "racer-tui's car", "the action space"

    @property
    def top_speed(self) -> float:
        return self.levels[-1].speed

    def steering_curvature(self, steering_deg: float, speed: FloatArray) -> FloatArray:
        """The steady curvature a steering angle gives at `speed`."""
        scale = self.effective_wheelbase * (1.0 + self.understeer * np.square(speed))
        return np.asarray(math.tan(math.radians(steering_deg)) / scale)

    def corner_speed(self, curvature: FloatArray) -> FloatArray:
        """The fastest steady speed on each `curvature` (1/m, either sign): within the
        grip and the steering of one of the car's speed levels; the slowest level when
        none can hold it (the line asks more than the car has)."""
        bend = np.maximum(np.abs(np.asarray(curvature, dtype=np.float64)), 1e-9)
        grip_speed = np.sqrt(self.grip / bend)
        best = np.zeros(bend.shape)
        for level in self.levels:
            if self.continuous:
                # Any speed up to the level: the grip's, and the steering's where it binds.
                speed = np.minimum(grip_speed, level.speed)
                held = self.steering_curvature(level.steering_deg, speed) >= bend
                speed = np.where(held, speed, self._steering_speed(level.steering_deg, bend))
            else:
                speed = np.full(bend.shape, level.speed)
                held = (speed <= grip_speed + 1e-9) & (
                    self.steering_curvature(level.steering_deg, speed) >= bend
                )
                speed = np.where(held, speed, 0.0)
            best = np.maximum(best, speed)
        return np.maximum(best, self.crawl)

    def _steering_speed(self, steering_deg: float, bend: FloatArray) -> FloatArray:
        """The fastest speed at which `steering_deg` still gives curvature `bend` (understeer
        makes the turn wider with speed); 0 where it never does."""
        reach = math.tan(math.radians(steering_deg)) / (self.effective_wheelbase * bend)
        if self.understeer <= 0.0:
            return np.where(reach >= 1.0, np.inf, 0.0)
        return np.sqrt(np.maximum(reach - 1.0, 0.0) / self.understeer)


def car_limits(car: CarSpec = DEEPRACER_CAR, space: ActionSpace | None = None) -> CarLimits:
    """The limits of `car` driving any action (racer-tui's car: 4 m/s, 30 degrees), or
    only those of `space`."""
    if space is None:
        levels: tuple[SpeedLevel, ...] = (
            SpeedLevel(car.max_speed * car.speed_gain, car.max_steering_deg),
        )
        continuous, label = True, "racer-tui's car"
        crawl = car.min_speed * car.speed_gain
    elif space.kind == "continuous":
        steering = min(max(abs(a) for a in space.steering_range), car.max_steering_deg)
        top = min(space.speed_range[1], car.max_speed) * car.speed_gain
        levels, continuous, label = (SpeedLevel(top, steering),), True, "the action space"
        crawl = max(space.speed_range[0], car.min_speed) * car.speed_gain
    else:
        widest: dict[float, float] = {}
        for action in space.actions:
            speed = min(max(action.speed, car.min_speed), car.max_speed) * car.speed_gain
            angle = min(abs(action.steering_angle), car.max_steering_deg)
            widest[speed] = max(widest.get(speed, 0.0), angle)
        levels = tuple(SpeedLevel(speed, widest[speed]) for speed in sorted(widest))
        continuous, label = False, "the action space"
        crawl = levels[0].speed
    return CarLimits(
        grip=car.grip,
        acceleration=car.max_acceleration,
        braking=car.max_braking,
        effective_wheelbase=car.effective_wheelbase,
        understeer=car.understeer,
        steering_lag=car.steering_time_constant * (1.0 - car.steering_instant_share),
        levels=levels,
        continuous=continuous,
        crawl=crawl,
        label=label,
    )

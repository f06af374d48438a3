"""DeepRacer's simulated car as pymunk bodies, stepped for many cars at once.

The car is a 0.324 m x 0.196 m box with a 0.164 m wheelbase and bicycle steering.
Actions are targets: the steering servo turns towards its target at a limited rate and
the motor approaches the target speed with a lag, as on the real car.

A grip limit makes racing non-trivial: the tyres can give at most `grip` m/s^2 of lateral
acceleration. Ask for a tighter turn than that at speed and the car understeers - the
path curvature saturates at grip / v^2, the car runs wide and scrubs speed. So the fastest
lap needs braking before corners and a racing line, never "full speed everywhere".

pymunk integrates the bodies and resolves contacts with boxes and other cars; the tyre
model sets each body's velocity every physics sub-step. All cars share one space and are
read and written in bulk through `pymunk.batch`, so stepping 64 cars costs little more
than stepping one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk
import pymunk.batch as pmb
from numpy.typing import NDArray

from sim.geometry import FloatArray

STEP_HZ = 15  # DeepRacer's camera and control rate
STEP_SECONDS = 1.0 / STEP_HZ
PHYSICS_SUBSTEPS = 4
# The version of the car's handling. Lap times of different versions are not comparable:
# league records carry it and leaderboards keep versions apart. Bump it with any change
# to the car that changes lap times.
PHYSICS_VERSION = 1

# Collision categories: cars never collide with each other unless a race asks for it
# (training runs many independent cars in one space).
_CAR_CATEGORY = 0b01
_OBSTACLE_CATEGORY = 0b10
_CAR_COLLISION_TYPE = 1
_BODY_FIELDS_STATE = pmb.BodyFields.POSITION | pmb.BodyFields.ANGLE
_BODY_FIELDS_MOTION = pmb.BodyFields.VELOCITY | pmb.BodyFields.ANGULAR_VELOCITY


@dataclass(frozen=True)
class CarSpec:
    """Dimensions and limits of DeepRacer's car (1/18 scale)."""

    length: float = 0.324
    width: float = 0.196
    wheelbase: float = 0.164
    wheel_track: float = 0.160  # distance between left and right wheel centres
    mass: float = 1.5
    max_steering_deg: float = 30.0
    min_speed: float = 0.1
    max_speed: float = 4.0
    steering_rate_deg: float = 300.0  # servo: full lock in 0.1 s
    speed_time_constant: float = 0.15  # motor lag towards the target speed
    max_acceleration: float = 4.0
    max_braking: float = 6.0
    grip: float = 7.0  # lateral acceleration limit, m/s^2
    scrub: float = 3.0  # speed lost per second per unit of asked-for-but-missing grip

    def corner_speed(self, radius: float) -> float:
        """The fastest steady speed on a circle of `radius` metres at the grip limit."""
        return min(self.max_speed, math.sqrt(self.grip * max(radius, 1e-9)))

    @property
    def min_turn_radius(self) -> float:
        """Radius of the rear axle's path at full lock."""
        return self.wheelbase / math.tan(math.radians(self.max_steering_deg))

    @property
    def wheel_offsets(self) -> FloatArray:
        """Wheel centres in the car frame (forward, left): FL, FR, RL, RR."""
        half_base, half_track = self.wheelbase / 2.0, self.wheel_track / 2.0
        return np.array(
            [
                [half_base, half_track],
                [half_base, -half_track],
                [-half_base, half_track],
                [-half_base, -half_track],
            ]
        )


DEEPRACER_CAR = CarSpec()


class Fleet:
    """N cars in one pymunk space, stepped together at 15 Hz.

    State lives in pymunk (pose, velocity); the actuator state (current steering angle,
    longitudinal speed) lives here. Read `x`, `y`, `yaw` after `step`.
    """

    def __init__(
        self,
        n_cars: int,
        spec: CarSpec = DEEPRACER_CAR,
        *,
        substeps: int = PHYSICS_SUBSTEPS,
        cars_collide: bool = False,
    ) -> None:
        if n_cars < 1:
            raise ValueError("a fleet needs at least one car")
        self.n = n_cars
        self.spec = spec
        self.substeps = substeps
        self.dt = STEP_SECONDS / substeps
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        car_mask = _OBSTACLE_CATEGORY | (_CAR_CATEGORY if cars_collide else 0)
        moment = pymunk.moment_for_box(spec.mass, (spec.length, spec.width))
        self.bodies: list[pymunk.Body] = []
        for _ in range(n_cars):
            body = pymunk.Body(spec.mass, moment)
            shape = pymunk.Poly.create_box(body, (spec.length, spec.width))
            shape.filter = pymunk.ShapeFilter(categories=_CAR_CATEGORY, mask=car_mask)
            shape.collision_type = _CAR_COLLISION_TYPE
            shape.friction = 0.8
            self.space.add(body, shape)
            self.bodies.append(body)
        self._index_of_body = {body.id: i for i, body in enumerate(self.bodies)}
        self._cars_collide = cars_collide
        self._has_obstacles = False
        self._bodies_stale = False  # poses moved on without pymunk (see `step`)

        self.x = np.zeros(n_cars)
        self.y = np.zeros(n_cars)
        self.yaw = np.zeros(n_cars)
        self.speed = np.zeros(n_cars)  # longitudinal speed of the rear axle, m/s
        self.steering = np.zeros(n_cars)  # current wheel angle, radians
        self.yaw_rate = np.zeros(n_cars)
        self.target_speed = np.zeros(n_cars)
        self.target_steering = np.zeros(n_cars)
        self.sliding = np.zeros(n_cars, dtype=bool)  # asked for more grip than there is
        self.crashed = np.zeros(n_cars, dtype=bool)  # touched a box or another car this step

        self._bind_motion_buffer(extra_bodies=0)
        self._state_buffer = pmb.Buffer()
        self._max_steer = math.radians(spec.max_steering_deg)
        self._steer_step = math.radians(spec.steering_rate_deg) * self.dt

    def _bind_motion_buffer(self, extra_bodies: int) -> None:
        # pymunk.batch walks every body in the space - cars first (they are dynamic), then
        # the static body once obstacles hang on it - so the buffer needs a row for each.
        self._motion_rows = np.zeros((self.n + extra_bodies, 3))
        self._motion = self._motion_rows[: self.n]
        self._motion_buffer = pmb.Buffer()
        self._motion_buffer.set_float_buf(self._motion_rows.reshape(-1))

    # --- placing cars and obstacles ------------------------------------------------------
    def place(self, car: int, x: float, y: float, yaw: float, speed: float = 0.0) -> None:
        """Teleport one car (start of an episode, or put back on the track after an off-track)."""
        body = self.bodies[car]
        body.position = (x, y)
        body.angle = yaw
        body.velocity = (speed * math.cos(yaw), speed * math.sin(yaw))
        body.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(body)
        self.x[car], self.y[car], self.yaw[car] = x, y, yaw
        self.speed[car] = speed
        self.steering[car] = 0.0
        self.yaw_rate[car] = 0.0
        self.target_speed[car] = speed
        self.target_steering[car] = 0.0
        self.sliding[car] = False
        self.crashed[car] = False

    def add_box(self, x: float, y: float, yaw: float, length: float, width: float) -> pymunk.Shape:
        """A static box (DeepRacer's object-avoidance obstacles are 0.3 m boxes)."""
        shape = pymunk.Poly.create_box(self.space.static_body, (length, width))
        transform = pymunk.Transform.translation(x, y).rotated(yaw)
        shape = pymunk.Poly(self.space.static_body, shape.get_vertices(), transform=transform)
        shape.filter = pymunk.ShapeFilter(categories=_OBSTACLE_CATEGORY)
        self.space.add(shape)
        if not self._has_obstacles:
            self._bind_motion_buffer(extra_bodies=1)
        self._has_obstacles = True
        return shape

    # --- actions -------------------------------------------------------------------------
    def set_targets(self, steering_deg: FloatArray, speed: FloatArray) -> None:
        """Actions are targets: clipped to the car's limits, reached with lag in `step`."""
        # np.minimum/np.maximum: np.clip's result at a fraction of its per-call overhead.
        self.target_steering[:] = np.minimum(
            np.maximum(np.radians(steering_deg), -self._max_steer), self._max_steer
        )
        self.target_speed[:] = np.minimum(
            np.maximum(speed, self.spec.min_speed), self.spec.max_speed
        )

    # --- physics -------------------------------------------------------------------------
    def step(self) -> None:
        """Advance every car by one control step (1/15 s)."""
        self.crashed[:] = False
        if self._has_obstacles or self._cars_collide:
            self._sync_bodies()
            for _ in range(self.substeps):
                self._update_actuators()
                self._apply_tyre_model()
                pmb.set_space_bodies(self.space, _BODY_FIELDS_MOTION, self._motion_buffer)
                self.space.step(self.dt)
                self._read_back()
                self._collect_contacts()
        elif self.n == 1:
            self._step_one_free_car()
        else:
            for _ in range(self.substeps):
                self._update_actuators()
                self._apply_tyre_model()
                self._integrate()
        self._bodies_stale = not (self._has_obstacles or self._cars_collide)

    # Nothing to collide with: pymunk would only integrate p += v dt, a += w dt (no forces,
    # no damping), so those steps do it directly - the same arithmetic, without a round trip
    # through the space. The bodies catch up in `_sync_bodies` if obstacles arrive later.
    def _integrate(self) -> None:
        motion, dt = self._motion, self.dt
        self.x = self.x + motion[:, 0] * dt
        self.y = self.y + motion[:, 1] * dt
        self.yaw = self.yaw + motion[:, 2] * dt

    def _step_one_free_car(self) -> None:
        """`step` for a lone car with nothing to hit, in plain floats: a race's hot path.

        The same formulas as `_update_actuators`, `_apply_tyre_model` and `_integrate`,
        without the per-call overhead of numpy on length-1 arrays.
        """
        spec, dt = self.spec, self.dt
        steer_step = self._steer_step
        max_down, max_up = -spec.max_braking * dt, spec.max_acceleration * dt
        lag = dt / spec.speed_time_constant
        grip, scrub, wheelbase = spec.grip, spec.scrub, spec.wheelbase
        half_base = wheelbase / 2.0
        target_steering = float(self.target_steering[0])
        target_speed = float(self.target_speed[0])
        steering = float(self.steering[0])
        speed = float(self.speed[0])
        x, y, yaw = float(self.x[0]), float(self.y[0]), float(self.yaw[0])
        yaw_rate = 0.0
        sliding = False
        for _ in range(self.substeps):
            steering += min(max(target_steering - steering, -steer_step), steer_step)
            speed += min(max((target_speed - speed) * lag, max_down), max_up)
            asked = math.tan(steering) / wheelbase
            grip_curvature = grip / max(speed * speed, 1e-6)
            curvature = min(max(asked, -grip_curvature), grip_curvature)
            overload = abs(asked) / grip_curvature - 1.0
            sliding = overload > 0.0
            speed = max(speed - min(max(overload, 0.0), 1.0) * scrub * dt, 0.0)
            yaw_rate = speed * curvature
            cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
            lateral = yaw_rate * half_base
            x += (speed * cos_yaw - lateral * sin_yaw) * dt
            y += (speed * sin_yaw + lateral * cos_yaw) * dt
            yaw += yaw_rate * dt
        self.steering[0] = steering
        self.speed = np.array([speed])
        self.yaw_rate = np.array([yaw_rate])
        self.sliding = np.array([sliding])
        self.x, self.y, self.yaw = np.array([x]), np.array([y]), np.array([yaw])

    def _sync_bodies(self) -> None:
        """Bring pymunk's bodies up to date after steps that integrated without them."""
        if not self._bodies_stale:
            return
        for car, body in enumerate(self.bodies):
            body.position = (float(self.x[car]), float(self.y[car]))
            body.angle = float(self.yaw[car])
            self.space.reindex_shapes_for_body(body)
        self._bodies_stale = False

    def _update_actuators(self) -> None:
        spec, dt = self.spec, self.dt
        # np.minimum/np.maximum rather than np.clip: same result, a fraction of the overhead
        # on small arrays, and this runs four times per step.
        steer_error = self.target_steering - self.steering
        self.steering += np.minimum(np.maximum(steer_error, -self._steer_step), self._steer_step)
        wanted = (self.target_speed - self.speed) * (dt / spec.speed_time_constant)
        self.speed += np.minimum(
            np.maximum(wanted, -spec.max_braking * dt), spec.max_acceleration * dt
        )

    def _apply_tyre_model(self) -> None:
        spec = self.spec
        speed = self.speed
        asked_curvature = np.tan(self.steering) / spec.wheelbase
        grip_curvature = spec.grip / np.maximum(speed * speed, 1e-6)
        curvature = np.minimum(np.maximum(asked_curvature, -grip_curvature), grip_curvature)
        overload = np.abs(asked_curvature) / grip_curvature - 1.0
        self.sliding = overload > 0.0
        # Scrubbing tyres bleed speed in proportion to how far past the limit they are.
        scrub = np.minimum(np.maximum(overload, 0.0), 1.0) * spec.scrub * self.dt
        self.speed = np.maximum(speed - scrub, 0.0)
        self.yaw_rate = self.speed * curvature
        cos_yaw, sin_yaw = np.cos(self.yaw), np.sin(self.yaw)
        # Bicycle model about the rear axle: the body centre (half a wheelbase ahead)
        # also moves sideways with the yaw rate.
        lateral = self.yaw_rate * (spec.wheelbase / 2.0)
        motion = self._motion
        motion[:, 0] = self.speed * cos_yaw - lateral * sin_yaw
        motion[:, 1] = self.speed * sin_yaw + lateral * cos_yaw
        motion[:, 2] = self.yaw_rate

    def _read_back(self) -> None:
        buffer = self._state_buffer
        buffer.clear()
        pmb.get_space_bodies(self.space, _BODY_FIELDS_STATE, buffer)
        state = np.frombuffer(buffer.float_buf(), dtype=np.float64).reshape(-1, 3)[: self.n]
        self.x = state[:, 0].copy()
        self.y = state[:, 1].copy()
        self.yaw = state[:, 2].copy()

    def _collect_contacts(self) -> None:
        if not (self._has_obstacles or self._cars_collide):
            return
        buffer = pmb.Buffer()
        pmb.get_space_arbiters(
            self.space, pmb.ArbiterFields.BODY_A_ID | pmb.ArbiterFields.BODY_B_ID, buffer
        )
        ids: NDArray[np.uintp] = np.frombuffer(buffer.int_buf(), dtype=np.uintp)
        for body_id in ids:
            car = self._index_of_body.get(int(body_id))
            if car is not None:
                self.crashed[car] = True

    # --- derived positions ---------------------------------------------------------------
    def points_ahead(self, distance: float) -> FloatArray:
        """(N, 2) points `distance` metres ahead of each body centre along its heading."""
        return np.stack(
            [self.x + distance * np.cos(self.yaw), self.y + distance * np.sin(self.yaw)], axis=1
        )

    def wheel_positions(self) -> FloatArray:
        """(N, 4, 2) wheel centres in world coordinates: FL, FR, RL, RR."""
        offsets = self.spec.wheel_offsets
        cos_yaw, sin_yaw = np.cos(self.yaw)[:, None], np.sin(self.yaw)[:, None]
        wx = self.x[:, None] + offsets[:, 0] * cos_yaw - offsets[:, 1] * sin_yaw
        wy = self.y[:, None] + offsets[:, 0] * sin_yaw + offsets[:, 1] * cos_yaw
        return np.stack([wx, wy], axis=2)

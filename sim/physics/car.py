"""DeepRacer's simulated car as pymunk bodies, stepped for many cars at once.

The car is a 0.324 m x 0.196 m box whose wheel centres span 0.164 m (wheelbase) by 0.160 m,
as in deepracer-simapp's URDF; those wheel centres decide on-track and off-track. How the
car *turns* is calibrated separately, on DeepRacer's own sim-traces: its simulated front
tyres slip, so a steering angle gives the curvature of a 0.27 m wheelbase, answering with a
quick share and a first-order lag (see `CarSpec` for each number and where it came from, and
`python -m benchmarks.sim.calibration` for the replay that checks them). The rear axle does not
slip sideways, so the body turns about it.

Actions are targets: the steering approaches its target with a lag and the motor the
target speed with a lag and acceleration limits, as in DeepRacer's simulator.

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

from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.foundation.arrays import FloatArray

STEP_HZ = 15  # DeepRacer's camera and control rate
STEP_SECONDS = 1.0 / STEP_HZ
PHYSICS_SUBSTEPS = 4
# The version of the simulated car: its handling and what its camera sees. Lap times of
# different versions are not comparable: league records carry it and leaderboards keep
# versions apart. Bump it with any change to the car or its sensors that changes lap
# times. 2: steering gain, steering lag and motor response calibrated on DeepRacer's
# sim-traces, and DeepRacer's own camera and scene (issue 25). 3: the steering takes a
# share of each command at once and the rest with a slower lag, as DeepRacer's traces
# show once they are replayed at their own command times. 4: the camera sits as it does on
# DeepRacer's car at rest, whose chassis tips 1.39 degrees nose-up on its wheels: it looks
# less far down, from a little higher (`sim.sensors.camera`).
PHYSICS_VERSION = 4

# Collision categories: cars never collide with each other unless a race asks for it
# (training runs many independent cars in one space).
_CAR_CATEGORY = 0b01
_OBSTACLE_CATEGORY = 0b10
_CAR_COLLISION_TYPE = 1
_BODY_FIELDS_STATE = pmb.BodyFields.POSITION | pmb.BodyFields.ANGLE
_BODY_FIELDS_MOTION = pmb.BodyFields.VELOCITY | pmb.BodyFields.ANGULAR_VELOCITY


@dataclass(frozen=True)
class CarSpec:
    """Dimensions, limits and handling of DeepRacer's car (1/18 scale).

    The defaults are the car DeepRacer's simulator drives today: deepracer-simapp picks its
    "deepracer_kinematics" car (steering hinges and wheels set by position and velocity
    controllers, `config/racecar_control_kinematics.yaml`) for models whose
    `model_metadata.json` version is 5 or more (`launch/racetrack_with_racecar.launch.py`),
    which is what racer-tui writes (`sim.deepracer.files.METADATA_VERSION`). Facts about
    simapp are from aws-deepracer-community/deepracer-simapp at 01f5f015 (`bundle/`). The
    handling constants were fitted by
    replaying the commands of DeepRacer sim-traces open-loop through this car (see
    `benchmarks.sim.calibration`): a DeepRacer-on-AWS continuous-action training run (simapp 6.0,
    15 iterations, 10,700 rows) and a DRoA training run, both from the public test data of
    aws-deepracer-community/deepracer-utils (`tests/deepracer/logs/`); checked on a DRoA
    evaluation (3 laps, simapp 6.0) that was not fitted.
    """

    length: float = 0.324
    width: float = 0.196
    # Wheel centres (simapp URDF `deepracer_single_cam.urdf`: rear axle 0.0817 m behind the
    # body origin, steering hinges 0.0823 m ahead, 0.081 m to each side). They decide
    # `all_wheels_on_track` and off-track, and the rear axle is the point that does not slip
    # sideways (in the traces the body centre's side-slip is 0.08 m x curvature).
    wheelbase: float = 0.164
    wheel_track: float = 0.160  # distance between left and right wheel centres
    mass: float = 1.5
    max_steering_deg: float = MAX_STEERING  # DeepRacer's limits (sim.deepracer.vocabulary)
    min_speed: float = MIN_SPEED
    max_speed: float = MAX_SPEED
    # Curvature = tan(steering) / (effective_wheelbase * (1 + understeer * v^2)). simapp sends
    # one angle to both steering hinges (no Ackermann: `send_action` in
    # `markov/agent_ctrl/utils.py`) and drives all four wheels at one speed, and its tyres
    # slip (mu 0.5 in `urdf/deepracer/racecar.gazebo`), so the car turns as if its
    # wheelbase were 0.26 m, not 0.164 m: fitted 0.264 m (path curvature 0.66 /m at 10
    # degrees and 1.7 /m at 25 degrees, 1 m/s). The traces show the curvature falling a
    # little with speed: 3.5 % from 1 to 2 m/s (understeer 0.012 s^2/m^2). Fitted at
    # 1-2.5 m/s; faster than that it is extrapolated.
    effective_wheelbase: float = 0.264
    understeer: float = 0.012
    # The steering: a new command moves the wheels 11 % of the way at once, the rest with a
    # first-order lag of 0.166 s (fitted; as one plain lag, 0.134 s fits the traces worse
    # and answers 13 % sooner than DeepRacer on the evaluation that checks it).
    steering_time_constant: float = 0.166
    steering_instant_share: float = 0.11
    # A pull: the wheels settle this many degrees left of every command (negative: right).
    # The kinematics car has none (fitted: +0.0 and +0.2 degrees on the two DRoA traces).
    steering_offset_deg: float = 0.0
    # The motor: the car settles at 1.02 x the commanded speed (simapp turns m/s into wheel
    # spin with a 0.035 m radius, `get_wheel_radius`; the traces' speed over the commanded
    # one: 1.01-1.02), reached within a few steps: from standing, 2.5 m/s in about 4 steps
    # (fitted: 0.03 s lag, 10 m/s^2 up, 15 m/s^2 down; the traces hold nothing faster).
    speed_gain: float = 1.02
    speed_time_constant: float = 0.03
    max_acceleration: float = 10.0
    max_braking: float = 15.0
    # Not calibrated: DeepRacer's traces stay under about 7 m/s^2 sideways.
    grip: float = 7.0  # lateral acceleration limit, m/s^2
    scrub: float = 3.0  # speed lost per second per unit of asked-for-but-missing grip

    def corner_speed(self, radius: float) -> float:
        """The fastest steady speed on a circle of `radius` metres at the grip limit."""
        return min(self.max_speed, math.sqrt(self.grip * max(radius, 1e-9)))

    def steering_for(self, curvature: FloatArray | float, speed: FloatArray | float) -> FloatArray:
        """The steering angle (radians) whose steady curvature at `speed` is `curvature`."""
        scale = self.effective_wheelbase * (1.0 + self.understeer * speed * speed)
        return np.asarray(np.arctan(curvature * scale) - math.radians(self.steering_offset_deg))

    @property
    def min_turn_radius(self) -> float:
        """Radius of the rear axle's path at full lock, slowly."""
        return self.effective_wheelbase / math.tan(math.radians(self.max_steering_deg))

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

# The car of simapp 3 and 4 (models of metadata version 3 or 4, e.g. what the console trained
# until 2022): its "deepracer" URDF drives the steering hinges with effort PD controllers
# (p 1.0, d 0.5 in `racecar_control.yaml`) and the wheels with effort P controllers, so it
# steers and accelerates far more slowly. Same wheel geometry. Fitted by replaying 130
# sim-traces of deepracer-utils' test data (simapp 4.0: the console's training run, two
# DeepRacer-for-Cloud runs' training and evaluations) at their own command times; the
# console's evaluations, the shared one among them (`../shared/deepracer/console-logs/`),
# were not fitted and check it. What the traces show, and what simapp explains of it:
# - a new command moves the hinges a little at once (9 % of it), as a PD controller's kick
#   on a step would, and the rest follows a slow lag (0.39 s; the PD's d/p is 0.5 s);
# - the car pulls left: every command turns as if it were 1.9 degrees further left, alike
#   in all six groups of traces (+2.1 to +3.1 degrees fitted apart; the URDF turns both
#   front wheels slightly left, 0.13 and 0.38 degrees, which cannot explain it all).
#   Today's car has no pull;
# - it turns as if its wheelbase were 0.30 m, and no tighter than 3.1 m/s^2 sideways (its
#   tyres' mu is 0.5; the wheels driven at one speed scrub each other), which is where its
#   curvature at 3 m/s and full lock levels off.
# For racing models trained on that car (`car_for_simapp_version`); not racer-tui's own.
SIMAPP4_CAR = CarSpec(
    effective_wheelbase=0.297,
    understeer=0.0,
    steering_time_constant=0.386,
    steering_offset_deg=1.92,
    steering_instant_share=0.09,
    speed_gain=1.02,
    speed_time_constant=0.19,
    max_acceleration=4.4,
    max_braking=18.0,
    grip=3.1,
)


def car_for_simapp_version(version: float) -> CarSpec:
    """The car DeepRacer's simulator drives for a model of this metadata version: simapp's
    `racetrack_with_racecar` launch picks the kinematics car from version 5 on."""
    return DEEPRACER_CAR if version >= 5.0 else SIMAPP4_CAR


def _blend(dt: float, time_constant: float) -> float:
    """The fraction of a first-order lag's error closed in `dt` (explicit Euler, as fitted)."""
    return 1.0 if time_constant <= 0.0 else min(dt / time_constant, 1.0)


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
        # The part of the wheel angle that follows the command with a lag (all of it unless
        # the car takes a share of each command at once: `CarSpec.steering_instant_share`).
        self._lagged_steering = np.zeros(n_cars)
        self.yaw_rate = np.zeros(n_cars)
        self.target_speed = np.zeros(n_cars)
        self.target_steering = np.zeros(n_cars)
        self.sliding = np.zeros(n_cars, dtype=bool)  # asked for more grip than there is
        self.crashed = np.zeros(n_cars, dtype=bool)  # touched a box or another car this step

        self._bind_motion_buffer(extra_bodies=0)
        self._state_buffer = pmb.Buffer()
        self._max_steer = math.radians(spec.max_steering_deg)
        self._steering_offset = math.radians(spec.steering_offset_deg)
        # Both lags as the fraction of the remaining error closed per physics sub-step.
        self._steer_blend = _blend(self.dt, spec.steering_time_constant)
        self._speed_blend = _blend(self.dt, spec.speed_time_constant)

    def _bind_motion_buffer(self, extra_bodies: int) -> None:
        # pymunk.batch walks every body in the space - cars first (they are dynamic), then
        # the static body once obstacles hang on it - so the buffer needs a row for each.
        self._motion_rows = np.zeros((self.n + extra_bodies, 3))
        self._motion = self._motion_rows[: self.n]
        self._motion_buffer = pmb.Buffer()
        self._motion_buffer.set_float_buf(self._motion_rows.reshape(-1))

    # --- placing cars and obstacles ------------------------------------------------------
    def place(
        self, car: int, x: float, y: float, yaw: float, speed: float = 0.0, *, steering: float = 0.0
    ) -> None:
        """Teleport one car (start of an episode, or put back on the track after an off-track).

        `steering` (radians) is where the wheels already point, and stay pointed until the
        next `set_targets`: a replay starting mid-trace needs it, a new episode does not.
        """
        body = self.bodies[car]
        body.position = (x, y)
        body.angle = yaw
        body.velocity = (speed * math.cos(yaw), speed * math.sin(yaw))
        body.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(body)
        self.x[car], self.y[car], self.yaw[car] = x, y, yaw
        self.speed[car] = speed
        self.steering[car] = steering
        self._lagged_steering[car] = steering
        self.yaw_rate[car] = 0.0
        self.target_speed[car] = speed
        self.target_steering[car] = steering
        self.sliding[car] = False
        self.crashed[car] = False

    def copy_car(self, other: Fleet, car: int) -> None:
        """Put every car of this fleet in the state of `other`'s car `car`, mid-drive (to try
        commands on copies of it; nothing to collide with, so no bodies are moved)."""
        for mine, theirs in (
            (self.x, other.x),
            (self.y, other.y),
            (self.yaw, other.yaw),
            (self.speed, other.speed),
            (self.steering, other.steering),
            (self._lagged_steering, other._lagged_steering),
            (self.yaw_rate, other.yaw_rate),
        ):
            mine[:] = theirs[car]
        self._bodies_stale = True

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
        single = self.n == 1 and isinstance(steering_deg, np.ndarray)
        if (
            single
            and steering_deg.dtype == np.float64
            and getattr(speed, "dtype", None) == np.float64
        ):
            # A race's one car: the same arithmetic in plain floats (math.radians and
            # np.radians both multiply by pi / 180), without numpy's per-call costs.
            steering = math.radians(float(steering_deg[0]))
            limit = self._max_steer
            self.target_steering[0] = min(max(steering, -limit), limit) + self._steering_offset
            spec = self.spec
            wanted = min(max(float(speed[0]), spec.min_speed), spec.max_speed)
            self.target_speed[0] = wanted * spec.speed_gain
            return
        # np.minimum/np.maximum: np.clip's result at a fraction of its per-call overhead.
        self.target_steering[:] = (
            np.minimum(np.maximum(np.radians(steering_deg), -self._max_steer), self._max_steer)
            + self._steering_offset
        )
        # DeepRacer's car settles a little above the commanded speed (`speed_gain`).
        self.target_speed[:] = (
            np.minimum(np.maximum(speed, self.spec.min_speed), self.spec.max_speed)
            * self.spec.speed_gain
        )

    # --- physics -------------------------------------------------------------------------
    def step(self) -> None:
        """Advance every car by one control step (1/15 s)."""
        self.advance(self.substeps)

    def advance(self, substeps: int) -> None:
        """Advance every car by `substeps` physics sub-steps (`dt` each). A control step is
        `self.substeps` of them; a replay of DeepRacer's irregular command times changes
        the targets between single sub-steps."""
        self.crashed[:] = False
        if self._has_obstacles or self._cars_collide:
            self._sync_bodies()
            for _ in range(substeps):
                self._update_actuators()
                self._apply_tyre_model()
                pmb.set_space_bodies(self.space, _BODY_FIELDS_MOTION, self._motion_buffer)
                self.space.step(self.dt)
                self._read_back()
                self._collect_contacts()
        elif self.n == 1:
            self._step_one_free_car(substeps)
        else:
            for _ in range(substeps):
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

    def _step_one_free_car(self, substeps: int) -> None:
        """`advance` for a lone car with nothing to hit, in plain floats: a race's hot path.

        The same formulas as `_update_actuators`, `_apply_tyre_model` and `_integrate`,
        without the per-call overhead of numpy on length-1 arrays.
        """
        spec, dt = self.spec, self.dt
        steer_blend, speed_blend = self._steer_blend, self._speed_blend
        max_down, max_up = -spec.max_braking * dt, spec.max_acceleration * dt
        grip, scrub = spec.grip, spec.scrub
        turning_base, understeer = spec.effective_wheelbase, spec.understeer
        half_base = spec.wheelbase / 2.0
        target_steering = float(self.target_steering[0])
        target_speed = float(self.target_speed[0])
        steering = float(self.steering[0])
        instant = spec.steering_instant_share
        lagged = float(self._lagged_steering[0])
        speed = float(self.speed[0])
        x, y, yaw = float(self.x[0]), float(self.y[0]), float(self.yaw[0])
        yaw_rate = 0.0
        sliding = False
        for _ in range(substeps):
            if instant:
                lagged += (target_steering - lagged) * steer_blend
                steering = instant * target_steering + (1.0 - instant) * lagged
            else:
                steering += (target_steering - steering) * steer_blend
            speed += min(max((target_speed - speed) * speed_blend, max_down), max_up)
            asked = math.tan(steering) / (turning_base * (1.0 + understeer * speed * speed))
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
        self._lagged_steering[0] = lagged if instant else steering
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
        instant = self.spec.steering_instant_share
        if instant:
            lagged = self._lagged_steering
            lagged += (self.target_steering - lagged) * self._steer_blend
            self.steering = instant * self.target_steering + (1.0 - instant) * lagged
        else:
            self.steering += (self.target_steering - self.steering) * self._steer_blend
        wanted = (self.target_speed - self.speed) * self._speed_blend
        self.speed += np.minimum(
            np.maximum(wanted, -spec.max_braking * dt), spec.max_acceleration * dt
        )

    def _apply_tyre_model(self) -> None:
        spec = self.spec
        speed = self.speed
        asked_curvature = np.tan(self.steering) / (
            spec.effective_wheelbase * (1.0 + spec.understeer * speed * speed)
        )
        grip_curvature = spec.grip / np.maximum(speed * speed, 1e-6)
        curvature = np.minimum(np.maximum(asked_curvature, -grip_curvature), grip_curvature)
        overload = np.abs(asked_curvature) / grip_curvature - 1.0
        self.sliding = overload > 0.0
        # Scrubbing tyres bleed speed in proportion to how far past the limit they are.
        scrub = np.minimum(np.maximum(overload, 0.0), 1.0) * spec.scrub * self.dt
        self.speed = np.maximum(speed - scrub, 0.0)
        self.yaw_rate = self.speed * curvature
        cos_yaw, sin_yaw = np.cos(self.yaw), np.sin(self.yaw)
        # Bicycle model about the rear axle, which does not slip: the body centre (half the
        # wheel centres' wheelbase ahead) also moves sideways with the yaw rate.
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

"""Car physics: DeepRacer's dimensions, its calibrated steering and motor, the grip limit,
determinism."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from sim.physics.car import DEEPRACER_CAR, SIMAPP4_CAR, STEP_HZ, STEP_SECONDS, Fleet


def drive(fleet: Fleet, steering: float, speed: float, steps: int) -> None:
    fleet.set_targets(np.full(fleet.n, steering), np.full(fleet.n, speed))
    for _ in range(steps):
        fleet.step()


def test_deepracer_dimensions() -> None:
    assert DEEPRACER_CAR.length == 0.324
    assert DEEPRACER_CAR.width == 0.196
    assert DEEPRACER_CAR.wheelbase == 0.164
    # The wheel centres span the real car (on-track rules and road gaps rely on it)...
    offsets = DEEPRACER_CAR.wheel_offsets
    assert math.isclose(offsets[:, 0].max() - offsets[:, 0].min(), 0.164)
    assert math.hypot(0.164, DEEPRACER_CAR.wheel_track) < 0.23
    # ...while it turns like DeepRacer's simulated car, whose front tyres slip.
    assert 0.25 < DEEPRACER_CAR.effective_wheelbase < 0.29
    shape = next(iter(Fleet(1).bodies[0].shapes))
    xs = [v.x for v in shape.get_vertices()]
    ys = [v.y for v in shape.get_vertices()]
    assert math.isclose(max(xs) - min(xs), 0.324)
    assert math.isclose(max(ys) - min(ys), 0.196)


def test_speed_is_reached_with_a_lag_not_instantly() -> None:
    fleet = Fleet(1)
    fleet.place(0, 0.0, 0.0, 0.0)
    drive(fleet, 0.0, 4.0, 1)
    assert 0.0 < fleet.speed[0] < 1.0  # one step (1/15 s) is far from 4 m/s
    drive(fleet, 0.0, 4.0, 3 * STEP_HZ)
    # DeepRacer's car settles a little above the commanded speed.
    assert math.isclose(fleet.speed[0], 4.0 * DEEPRACER_CAR.speed_gain, rel_tol=0.01)
    assert fleet.speed[0] > 4.0
    assert fleet.x[0] > 5.0


def test_steering_turns_left_for_positive_angles() -> None:
    fleet = Fleet(1)
    fleet.place(0, 0.0, 0.0, 0.0)
    drive(fleet, 20.0, 1.0, 10)
    assert fleet.y[0] > 0.0
    assert fleet.yaw[0] > 0.0
    assert 0.0 < fleet.steering[0] <= math.radians(20.0) + 1e-9


def test_steering_answers_with_a_first_order_lag() -> None:
    fleet = Fleet(1)
    fleet.place(0, 0.0, 0.0, 0.0)
    fleet.set_targets(np.array([30.0]), np.array([1.0]))
    fleet.step()
    assert 0.0 < fleet.steering[0] < math.radians(30.0)
    # About 63 % of the step after one time constant, nearly all of it after five.
    steps = round(DEEPRACER_CAR.steering_time_constant / STEP_SECONDS)
    fleet.place(0, 0.0, 0.0, 0.0)
    drive(fleet, 30.0, 1.0, steps)
    reached = fleet.steering[0] / math.radians(30.0)
    elapsed = steps * STEP_SECONDS / DEEPRACER_CAR.steering_time_constant
    assert abs(reached - (1.0 - math.exp(-elapsed))) < 0.08
    drive(fleet, 30.0, 1.0, 5 * steps)
    assert fleet.steering[0] > 0.97 * math.radians(30.0)


def test_a_placed_car_keeps_its_wheel_angle_until_told() -> None:
    fleet = Fleet(1)
    fleet.place(0, 0.0, 0.0, 0.0, 1.0, steering=math.radians(10.0))
    assert fleet.steering[0] == math.radians(10.0)
    fleet.step()  # no new target: the wheels stay where they were
    assert math.isclose(fleet.steering[0], math.radians(10.0))
    assert fleet.yaw[0] > 0.0


def test_slow_full_lock_turn_follows_the_bicycle_model() -> None:
    fleet = Fleet(1)
    fleet.place(0, 0.0, 0.0, 0.0)
    drive(fleet, 30.0, 1.0, 4 * STEP_HZ)
    radius = fleet.speed[0] / abs(fleet.yaw_rate[0])
    speed_factor = 1.0 + DEEPRACER_CAR.understeer * fleet.speed[0] ** 2
    assert math.isclose(radius, DEEPRACER_CAR.min_turn_radius * speed_factor, rel_tol=0.02)
    assert not fleet.sliding[0]


def test_curvature_follows_deepracers_steering_gain_and_falls_a_little_with_speed() -> None:
    """DeepRacer's traces: 0.64-0.69 /m at 10 degrees and 1.7-1.8 /m at 25 degrees (1 m/s),
    a few per cent less at 2 m/s."""
    curvature = {}
    for angle, speed in ((10.0, 1.0), (25.0, 1.0), (10.0, 2.0)):
        fleet = Fleet(1)
        fleet.place(0, 0.0, 0.0, 0.0, speed)
        drive(fleet, angle, speed / DEEPRACER_CAR.speed_gain, 2 * STEP_HZ)
        curvature[angle, speed] = fleet.yaw_rate[0] / fleet.speed[0]
    assert 0.60 < curvature[10.0, 1.0] < 0.70
    assert 1.55 < curvature[25.0, 1.0] < 1.85
    assert 0.90 < curvature[10.0, 2.0] / curvature[10.0, 1.0] < 0.99


def test_too_fast_for_the_corner_understeers_wide() -> None:
    slow, fast = Fleet(1), Fleet(1)
    for fleet in (slow, fast):
        fleet.place(0, 0.0, 0.0, 0.0)
    drive(slow, 15.0, 1.0, 3 * STEP_HZ)
    drive(fast, 15.0, 4.0, 3 * STEP_HZ)
    slow_radius = slow.speed[0] / abs(slow.yaw_rate[0])
    fast_radius = fast.speed[0] / abs(fast.yaw_rate[0])
    assert fast.sliding[0]
    assert fast_radius > 2.0 * slow_radius
    lateral_acceleration = fast.speed[0] * abs(fast.yaw_rate[0])
    assert lateral_acceleration <= DEEPRACER_CAR.grip + 1e-6
    assert fast.speed[0] < 4.0  # scrubbing tyres lose speed


def test_physics_is_deterministic() -> None:
    runs = []
    for _ in range(2):
        fleet = Fleet(3)
        for car in range(3):
            fleet.place(car, car * 1.0, 0.0, 0.1 * car)
        rng = np.random.default_rng(7)
        for _ in range(100):
            fleet.set_targets(rng.uniform(-30, 30, 3), rng.uniform(0.1, 4, 3))
            fleet.step()
        runs.append(np.concatenate([fleet.x, fleet.y, fleet.yaw]))
    assert np.array_equal(runs[0], runs[1])


def test_batched_cars_move_independently_like_single_cars() -> None:
    batch = Fleet(2)
    single = Fleet(1)
    batch.place(0, 0.0, 0.0, 0.0)
    batch.place(1, 5.0, 5.0, 1.0)
    single.place(0, 5.0, 5.0, 1.0)
    for _ in range(30):
        batch.set_targets(np.array([-10.0, 25.0]), np.array([2.0, 3.0]))
        single.set_targets(np.array([25.0]), np.array([3.0]))
        batch.step()
        single.step()
    assert math.isclose(batch.x[1], single.x[0], abs_tol=1e-9)
    assert math.isclose(batch.y[1], single.y[0], abs_tol=1e-9)


def test_cars_collide_only_when_asked() -> None:
    for collide in (False, True):
        fleet = Fleet(2, cars_collide=collide)
        fleet.place(0, 0.0, 0.0, 0.0)
        fleet.place(1, 0.6, 0.0, math.pi)
        fleet.set_targets(np.zeros(2), np.ones(2))
        touched = np.zeros(2, dtype=bool)
        for _ in range(15):
            fleet.step()
            touched |= fleet.crashed
        assert bool(touched.all()) is collide


def test_the_old_car_pulls_left_and_todays_does_not() -> None:
    """simapp 3-4's car turns as if every command were about two degrees further left (its
    sim-traces, `SIMAPP4_CAR`): told to go straight it drifts left; today's car keeps its
    line."""
    for spec, drifts in ((SIMAPP4_CAR, True), (DEEPRACER_CAR, False)):
        fleet = Fleet(1, spec)
        fleet.place(0, 0.0, 0.0, 0.0, 1.0)
        drive(fleet, 0.0, 1.0, 3 * STEP_HZ)
        assert bool(fleet.y[0] > 0.05) is drifts, spec
        assert fleet.yaw[0] >= 0.0
    # Its planner asks for a little right to go straight, and goes straight.
    fleet = Fleet(1, SIMAPP4_CAR)
    fleet.place(0, 0.0, 0.0, 0.0, 1.0)
    straight = float(np.degrees(SIMAPP4_CAR.steering_for(0.0, 1.0)))
    assert math.isclose(straight, -SIMAPP4_CAR.steering_offset_deg)
    drive(fleet, straight, 1.0, 3 * STEP_HZ)
    assert abs(fleet.y[0]) < 1e-6


def test_a_new_command_moves_the_wheels_a_share_at_once_and_the_rest_with_the_lag() -> None:
    """DeepRacer's steering hinges, in both its cars, answer a new command a little within
    a physics sub-step and then follow a lag (their traces); a plain lag moves less."""
    plain = dataclasses.replace(DEEPRACER_CAR, steering_instant_share=0.0)
    first = {}
    for spec in (SIMAPP4_CAR, DEEPRACER_CAR, plain):
        fleet = Fleet(1, spec)
        fleet.place(0, 0.0, 0.0, 0.0, 1.0)
        fleet.set_targets(np.array([30.0]), np.array([1.0]))
        fleet.advance(1)
        # The target is the command plus the car's pull.
        first[spec] = fleet.steering[0] / math.radians(30.0 + spec.steering_offset_deg)
        lag_alone = min(fleet.dt / spec.steering_time_constant, 1.0)
        share = spec.steering_instant_share
        assert math.isclose(first[spec], share + (1.0 - share) * lag_alone, rel_tol=1e-6)
    assert SIMAPP4_CAR.steering_instant_share > 0.0 and DEEPRACER_CAR.steering_instant_share > 0.0
    assert first[DEEPRACER_CAR] > first[plain]


def test_a_lone_car_and_a_fleet_drive_the_old_car_alike() -> None:
    """The lone car's float path and the fleet's arrays give the same steps, pull and share
    included."""
    lone, fleet = Fleet(1, SIMAPP4_CAR), Fleet(2, SIMAPP4_CAR)
    lone.place(0, 1.0, 2.0, 0.5, 1.0, steering=0.1)
    for car in range(2):
        fleet.place(car, 1.0, 2.0, 0.5, 1.0, steering=0.1)
    rng = np.random.default_rng(3)
    for _ in range(40):
        steering, speed = rng.uniform(-30, 30), rng.uniform(0.5, 3.0)
        lone.set_targets(np.array([steering]), np.array([speed]))
        fleet.set_targets(np.full(2, steering), np.full(2, speed))
        lone.step()
        fleet.step()
    assert math.isclose(lone.x[0], fleet.x[1], abs_tol=1e-9)
    assert math.isclose(lone.yaw[0], fleet.yaw[1], abs_tol=1e-9)
    assert math.isclose(lone.steering[0], fleet.steering[1], abs_tol=1e-12)


def test_a_step_is_its_physics_sub_steps() -> None:
    stepped, advanced = Fleet(2), Fleet(2)
    for fleet in (stepped, advanced):
        fleet.place(0, 0.0, 0.0, 0.0, 1.0)
        fleet.place(1, 1.0, 0.0, 0.3, 2.0)
        fleet.set_targets(np.array([12.0, -25.0]), np.array([2.0, 3.0]))
    stepped.step()
    for _ in range(advanced.substeps):
        advanced.advance(1)
    assert np.array_equal(stepped.x, advanced.x)
    assert np.array_equal(stepped.yaw, advanced.yaw)

"""Opponents in a training (sim.race.opponents): other cars driven by their own models on
the track with every training car, seen and judged as a head-to-head race's cars are."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.env import BatchedDeepRacer, EnvConfig
from sim.physics.simulation import TrackSimulation
from sim.race.driver import DriverAction, reference_driver
from sim.race.head_to_head import GRID_GAP
from sim.race.opponents import OPPONENT_RULES, OpponentField

TRACK = "reinvent_base"


class StandingDriver:
    """An opponent that stands where it is put (a parked car)."""

    name = "parked"
    content_hash = "parked"

    def reset(self, sim: TrackSimulation) -> None:
        del sim

    def act(self, sim: TrackSimulation) -> DriverAction:
        still = np.zeros(sim.n)
        return DriverAction(still, still.copy(), np.full(sim.n, -1, dtype=np.int64))


def fleet(
    cars: int, opponents: int = 1, sensors: tuple[str, ...] = ("lidar",), *, parked: bool = False
) -> BatchedDeepRacer:
    """`cars` training cars, each with `opponents` reference drivers (or parked cars) as
    opponents."""

    def field(sim: TrackSimulation) -> OpponentField:
        driver = StandingDriver() if parked else reference_driver(sim.track)
        return OpponentField(sim, [driver] * opponents, seed=7)

    config = EnvConfig.build(TRACK, sensors=sensors, objects_for=field)
    batch = BatchedDeepRacer(config, cars, seed=1)
    batch.reset()
    return batch


def field_of(batch: BatchedDeepRacer) -> OpponentField:
    objects = batch.sim.objects
    assert isinstance(objects, OpponentField)
    return objects


def along(length: float, a: float, b: float) -> float:
    """b ahead of a along the track (negative: behind), the short way round."""
    return (b - a + length / 2.0) % length - length / 2.0


def test_each_episode_starts_on_a_grid_with_the_training_car_in_a_free_lane() -> None:
    batch = fleet(cars=6, opponents=2)
    field = field_of(batch)
    sim, length = batch.sim, field.length
    grids = set()
    for car in range(sim.n):
        start = float(sim.start_s[car])
        gaps = [along(length, start, float(field.distance[car, k])) for k in range(2)]
        places = [round(gap / GRID_GAP) for gap in gaps]
        for gap, place in zip(gaps, places, strict=True):
            assert abs(gap - place * GRID_GAP) < 0.05  # on the grid, 0.75 m apart
        # The car and its two opponents fill three places in a row.
        assert sorted([0, *places]) == list(range(min([*places, 0]), min([*places, 0]) + 3))
        grids.add(tuple(places))
        for k in range(2):  # clear of both: the car takes the lane free of a near one
            apart = math.hypot(
                float(sim.fleet.x[car] - field.x[car, k]), float(sim.fleet.y[car] - field.y[car, k])
            )
            assert apart > 0.3
    assert len(grids) > 1  # the place is drawn: not every car starts in the same one


def test_opponents_drive_on_their_own_and_are_seen_in_the_reward_params() -> None:
    batch = fleet(cars=2)
    field = field_of(batch)
    opponent = field.sims[0]
    before = opponent.travelled.copy()
    for _ in range(20):  # the training cars stand where they started meanwhile
        field.advance(1 / 15)
    assert (opponent.travelled - before > 0.5).all()  # they drove on, metres of it
    params = batch.sim.all_params()
    for car in range(2):
        location = params[car]["objects_location"][0]
        assert location == pytest.approx([field.x[car, 0], field.y[car, 0]])
        assert params[car]["objects_speed"][0] == pytest.approx(float(opponent.fleet.speed[car]))
        assert params[car]["objects_speed"][0] > 0.5  # its own speed, not a bot's setting
        assert len(params[car]["objects_heading"]) == 1


def test_the_training_cars_lidar_sees_its_opponent_and_the_opponent_sees_it() -> None:
    batch = fleet(cars=1)
    field = field_of(batch)
    sim = batch.sim
    # The opponent 0.8 m straight ahead of the training car, in its path.
    x, y, yaw = float(sim.fleet.x[0]), float(sim.fleet.y[0]), float(sim.fleet.yaw[0])
    ahead = (x + 0.8 * math.cos(yaw), y + 0.8 * math.sin(yaw))
    field.sims[0].put(0, ahead[0], ahead[1], yaw, 0.0)
    field._follow()
    scan = batch.observer.observe()
    front = scan[0, len(scan[0]) // 2]
    assert front < 0.8  # the lidar's middle ray stops at the opponent's back
    seen = field.sims[0].objects
    assert seen is not None
    assert (float(seen.x[0, 0]), float(seen.y[0, 0])) == pytest.approx((x, y))


def test_the_car_behind_is_the_one_that_crashed() -> None:
    batch = fleet(cars=2)
    field = field_of(batch)
    sim = batch.sim
    # Car 0 runs into its opponent from behind; car 1's opponent runs into it from behind.
    for car, offset in ((0, 0.2), (1, -0.2)):
        x, y, yaw = float(sim.fleet.x[car]), float(sim.fleet.y[car]), float(sim.fleet.yaw[car])
        field.sims[0].put(car, x + offset * math.cos(yaw), y + offset * math.sin(yaw), yaw, 0.0)
    field._follow()
    crashed = field.crashed(sim.fleet.x, sim.fleet.y, sim.fleet.yaw, sim.s, sim.car)
    assert crashed.tolist() == [True, False]
    field.advance(1 / 15)
    assert field.hold_left[1, 0] == pytest.approx(OPPONENT_RULES.collision_penalty_seconds)
    assert field.hold_left[0, 0] == 0.0
    # A held opponent cannot be run into (simapp's blink).
    held = field.crashed(sim.fleet.x, sim.fleet.y, sim.fleet.yaw, sim.s, sim.car)
    assert not held[1]


def test_a_training_car_crashing_into_an_opponent_ends_its_episode_crashed() -> None:
    batch = fleet(cars=1, parked=True)
    field = field_of(batch)
    sim = batch.sim
    x, y, yaw = float(sim.fleet.x[0]), float(sim.fleet.y[0]), float(sim.fleet.yaw[0])
    field.sims[0].put(0, x + 0.5 * math.cos(yaw), y + 0.5 * math.sin(yaw), yaw, 0.0)
    field._follow()
    statuses = []
    full_ahead = np.array([[0.0, 1.0]], dtype=np.float32)
    for _ in range(15):
        _, _, terminated, _, infos = batch.step(full_ahead)
        statuses.append(infos[0].status)
        if terminated[0]:
            break
    assert statuses[-1] == EpisodeStatus.CRASHED


def test_the_same_seed_lines_the_same_grids_up() -> None:
    first, second = field_of(fleet(cars=4)), field_of(fleet(cars=4))
    assert np.array_equal(first.distance, second.distance)

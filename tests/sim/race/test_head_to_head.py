"""Head-to-head races as simapp runs HEAD_TO_MODEL (docs/deepracer/head-to-head-simapp.md):
the grid, what each car senses of the others, who is judged in a crash, how the race ends,
and the fixed points (a driver against itself, twice the same race)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.physics.car import DEEPRACER_CAR
from sim.physics.objects.rivals import RivalField
from sim.physics.simulation import TrackSimulation
from sim.race.driver import reference_driver
from sim.race.head_to_head import (
    GRID_GAP,
    Entry,
    HeadToHeadError,
    HeadToHeadRace,
    HeadToHeadResult,
    run_head_to_head,
)
from sim.race.rules import HEAD_TO_HEAD_RULES
from sim.sensors.observations import Observer
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track


@pytest.fixture(scope="module")
def track() -> Track:
    return resolve_track("reinvent_base")


def _race(track: Track, cars: int) -> HeadToHeadResult:
    driver = reference_driver(track)
    return run_head_to_head(
        track, HEAD_TO_HEAD_RULES, [Entry(f"r{i}", driver) for i in range(cars)]
    )


def _summary(result: HeadToHeadResult) -> list[tuple[int, tuple[float, ...], int]]:
    return [
        (
            finish.car,
            tuple(round(lap.time_seconds, 9) for lap in finish.result.laps),
            sum(lap.crashes for lap in finish.result.laps),
        )
        for finish in result.cars
    ]


def test_the_grid_is_simapps_staggered_lanes(track: Track) -> None:
    driver = reference_driver(track)
    race = HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver), Entry("b", driver)])
    sim = race.sim
    # Car 1 starts 0.75 m behind car 0, along the track; its lap starts below zero.
    assert float(sim.travelled[1]) == pytest.approx(float(sim.travelled[0]) - GRID_GAP, abs=0.05)
    # Even cars in the outer lane, odd in the inner: on reinvent_base (counter-clockwise)
    # the inner lane is on the left.
    assert not bool(sim.left_of_center[0]) and bool(sim.left_of_center[1])
    assert 0.1 < float(sim.distance_from_center[0]) < 0.4
    assert 0.1 < float(sim.distance_from_center[1]) < 0.4


def test_a_driver_against_itself_is_the_same_race_twice_and_the_front_car_wins(
    track: Track,
) -> None:
    first, second = _race(track, 2), _race(track, 2)
    assert _summary(first) == _summary(second)
    assert first.winner.car == 0  # the same driver: the car ahead on the grid stays ahead
    finished = first.winner.finished_at
    assert first.winner.laps_completed == 3 and finished is not None
    assert first.clock - 1 / 15 < finished <= first.clock  # the line crossed in the last step
    loser = first.cars[1]
    # The race ends when the winner completes its laps: the other is stopped short.
    assert loser.finished_at is None and loser.laps_completed < 3
    assert loser.gap_seconds is not None and loser.gap_seconds > 0


def test_only_the_car_behind_is_held_after_a_crash(track: Track) -> None:
    result = _race(track, 3)  # the third car closes on the second in the first turns
    crashes = [incident for incident in result.incidents if incident.kind == "crash"]
    assert crashes, "the three-car reference race has a crash to judge"
    by_car = {finish.car: finish.result for finish in result.cars}
    for crash in crashes:
        crashed_laps = by_car[crash.car].laps
        assert sum(lap.crashes for lap in crashed_laps) >= 1
        # The crash's hold is inside the lap's time, as simapp's frozen time is.
        assert any(lap.penalty_seconds >= 5.0 for lap in crashed_laps if lap.crashes)
        # The car it ran into is not judged for that crash.
        assert not any(other.car == crash.other and other.other == crash.car for other in crashes)
    assert _summary(result) == _summary(_race(track, 3))


def test_the_crash_rule_judges_the_car_behind_and_never_a_held_car(track: Track) -> None:
    sim = TrackSimulation(track, 2)
    field = RivalField(track, 2, sim.fleet)
    sim.objects = field
    sim.reset_cars([0, 1], [1.0, 1.0])
    sim.put(1, float(sim.fleet.x[0]) - 0.2, float(sim.fleet.y[0]), float(sim.fleet.yaw[0]))
    fleet = sim.fleet
    field.follow()
    field.standing = np.array([10.0, 9.8])  # car 1 is behind
    hit = field.crashed(fleet.x, fleet.y, fleet.yaw, sim.s, DEEPRACER_CAR)
    assert hit.tolist() == [False, True]
    field.standing = np.array([9.8, 10.0])  # now car 0 is
    assert field.crashed(fleet.x, fleet.y, fleet.yaw, sim.s, DEEPRACER_CAR).tolist() == [
        True,
        False,
    ]
    field.ghost[1] = True  # car 1 is serving a penalty: nobody runs into it, nor it
    assert field.crashed(fleet.x, fleet.y, fleet.yaw, sim.s, DEEPRACER_CAR).tolist() == [
        False,
        False,
    ]


def test_each_car_senses_the_other_as_simapp_lists_it(track: Track) -> None:
    driver = reference_driver(track)
    race = HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver), Entry("b", driver)])
    sim = race.sim
    # Put car 1 right behind car 0, in the same lane, facing it.
    x, y, yaw = float(sim.fleet.x[0]), float(sim.fleet.y[0]), float(sim.fleet.yaw[0])
    sim.put(1, x - 0.6 * math.cos(yaw), y - 0.6 * math.sin(yaw), yaw)
    race.rivals.follow()
    lidar = Observer(sim, ("lidar",)).observe()
    alone = TrackSimulation(track, 1)
    alone.put(0, float(sim.fleet.x[1]), float(sim.fleet.y[1]), yaw)
    lidar_alone = Observer(alone, ("lidar",)).observe()
    ahead = lidar.shape[1] // 2  # the middle ray points straight ahead
    assert lidar[1][ahead] < 0.5 < lidar_alone[0][ahead]
    camera = Observer(sim, ("camera",)).observe()
    camera_alone = Observer(alone, ("camera",)).observe()
    assert not np.array_equal(camera[1], camera_alone[0])  # the car ahead is drawn
    params = sim.all_params()
    assert params[1]["objects_location"] == [[pytest.approx(x), pytest.approx(y)]]
    assert params[1]["closest_objects"] == [0, 0]
    assert params[0]["objects_location"][0][0] == pytest.approx(float(sim.fleet.x[1]))


def test_a_race_takes_two_to_six_cars(track: Track) -> None:
    driver = reference_driver(track)
    for count in (1, 7):
        with pytest.raises(HeadToHeadError, match="2 to 6 cars"):
            HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver)] * count)

"""Head-to-head races as simapp runs HEAD_TO_MODEL (docs/deepracer/head-to-head-simapp.md):
the grid, what each car senses of the others, who is judged in a crash, how the race ends,
and the fixed points (a driver against itself, twice the same race)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from sim.physics.car import DEEPRACER_CAR
from sim.physics.objects.rivals import Grid, RivalField
from sim.physics.simulation import TrackSimulation
from sim.race.driver import DriverAction, reference_driver
from sim.race.head_to_head import (
    GRID_GAP,
    Entry,
    HeadToHeadError,
    HeadToHeadRace,
    HeadToHeadResult,
    run_head_to_head,
)
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.race.trace import IN_PROGRESS, LAP_COMPLETE, OFF_TRACK, PAUSE, REVERSED
from sim.sensors.observations import Observer
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track


@pytest.fixture(scope="module")
def track() -> Track:
    return resolve_track("reinvent_base")


def _race(track: Track, cars: int, rules: RaceRules = HEAD_TO_HEAD_RULES) -> HeadToHeadResult:
    driver = reference_driver(track)
    return run_head_to_head(track, rules, [Entry(f"r{i}", driver) for i in range(cars)])


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
    first, second = race.sims
    # Car 1 starts 0.75 m behind car 0, along the track; its lap starts below zero.
    assert float(second.travelled[0]) == pytest.approx(
        float(first.travelled[0]) - GRID_GAP, abs=0.05
    )
    # Even cars in the outer lane, odd in the inner: on reinvent_base (counter-clockwise)
    # the inner lane is on the left.
    assert not bool(first.left_of_center[0]) and bool(second.left_of_center[0])
    assert 0.1 < float(first.distance_from_center[0]) < 0.4
    assert 0.1 < float(second.distance_from_center[0]) < 0.4


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


class _Steady:
    """Straight on at a steady speed, whatever is in the way."""

    content_hash = "steady"

    def __init__(self, speed: float) -> None:
        self.speed = speed
        self.name = f"steady {speed:g}"

    def reset(self, sim: TrackSimulation) -> None:
        del sim

    def act(self, sim: TrackSimulation) -> DriverAction:
        return DriverAction(
            steering_deg=np.zeros(sim.n),
            speed=np.full(sim.n, self.speed),
            action_index=np.full(sim.n, -1, dtype=np.int64),
        )


def test_only_the_car_behind_is_held_after_a_crash(track: Track) -> None:
    rules = HEAD_TO_HEAD_RULES
    race = HeadToHeadRace(track, rules, [Entry("front", _Steady(0.0)), Entry("back", _Steady(1.0))])
    front, back = race.sims
    x, y, yaw = float(front.fleet.x[0]), float(front.fleet.y[0]), float(front.fleet.yaw[0])
    back.put(0, x - 0.5 * math.cos(yaw), y - 0.5 * math.sin(yaw), yaw)  # right behind it
    for _ in range(30):
        race.tick()
    crashes = [incident for incident in race.incidents if incident.kind == "crash"]
    assert [(crash.car, crash.other) for crash in crashes] == [(1, 0)]
    held = race.cars[1]
    assert held.lap_crashes == 1 and held.lap_penalty == rules.collision_penalty_seconds
    assert held.hold_left > 0 and bool(race.grid.ghost[1])
    assert race.cars[0].lap_crashes == 0 and race.cars[0].hold_left == 0.0
    # Held where it crashed: it does not move while the clock runs.
    where = (float(back.fleet.x[0]), float(back.fleet.y[0]))
    race.tick()
    assert (float(back.fleet.x[0]), float(back.fleet.y[0])) == where
    # After the hold it drives on, and runs into the car again: judged again (simapp).
    for _ in range(round(rules.collision_penalty_seconds * 15) + 30):
        race.tick()
    assert len([i for i in race.incidents if i.kind == "crash"]) == 2


def test_the_crash_rule_judges_the_car_behind_and_never_a_held_car(track: Track) -> None:
    sims = [TrackSimulation(track, 1) for _ in range(2)]
    grid = Grid.of([sim.fleet for sim in sims], track)
    sims[0].reset_car(0, 1.0)
    x, y, yaw = float(sims[0].fleet.x[0]), float(sims[0].fleet.y[0]), float(sims[0].fleet.yaw[0])
    sims[1].put(0, x - 0.2 * math.cos(yaw), y - 0.2 * math.sin(yaw), yaw)  # nose to tail
    fields = [RivalField(track, k, grid) for k in range(2)]

    def judged() -> list[list[int]]:
        return [field.crashed_into(DEEPRACER_CAR) for field in fields]

    grid.standing = np.array([10.0, 9.8])  # car 1 is behind
    assert judged() == [[], [0]]
    grid.standing = np.array([9.8, 10.0])  # now car 0 is
    assert judged() == [[1], []]
    # Laps do not count, where the cars are on the track does: car 1, a lap up, has run
    # into car 0 from behind as it laps it; and across the line the car short of it is.
    grid.standing = np.array([10.0, 9.8 + track.length])
    assert judged() == [[], [0]]
    grid.standing = np.array([0.1, track.length - 0.1])  # car 0 just past the line
    assert judged() == [[], [0]]
    grid.ghost[1] = True  # car 1 is serving a penalty: nobody runs into it, nor it
    assert judged() == [[], []]
    # A simulation never judges a crash with a rival itself: the race does, once all moved.
    assert (
        not fields[0]
        .crashed(sims[0].fleet.x, sims[0].fleet.y, sims[0].fleet.yaw, sims[0].s, DEEPRACER_CAR)
        .any()
    )


def test_one_pass_over_the_grid_judges_every_car_as_its_own_objects_would(
    track: Track,
) -> None:
    """`Grid.crashes` tests only the pairs close enough to touch, all in one go; each car's
    answer is the crash test against all of its rivals as objects, held cars left out."""
    rng = np.random.default_rng(4)
    sims = [TrackSimulation(track, 1) for _ in range(4)]
    grid = Grid.of([sim.fleet for sim in sims], track)
    fields = [RivalField(track, k, grid) for k in range(4)]
    crashes_seen = 0
    for _ in range(300):
        for sim in sims:  # four cars within a car's length or two of each other
            sim.put(0, 1.0 + rng.normal(0, 0.2), 0.5 + rng.normal(0, 0.2), rng.uniform(-3, 3))
        grid.standing = rng.uniform(0.0, track.length, 4)
        grid.ghost = rng.random(4) < 0.2
        expected = {}
        for me, field in enumerate(fields):
            field.follow()
            fleet = grid.fleets[me]
            hits = field.hits(fleet.x, fleet.y, fleet.yaw, DEEPRACER_CAR)[0].tolist()
            others = [j for j in range(4) if j != me]
            expected[me] = [
                other
                for other, hit in zip(others, hits, strict=True)
                if hit and not grid.ghost[me] and not grid.ghost[other] and grid.behind(me, other)
            ]
        assert grid.crashes(range(4), DEEPRACER_CAR) == expected
        crashes_seen += sum(len(found) for found in expected.values())
    assert crashes_seen > 50


def test_each_car_senses_the_other_as_simapp_lists_it(track: Track) -> None:
    driver = reference_driver(track)
    race = HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver), Entry("b", driver)])
    front, behind = race.sims
    # Put car 1 right behind car 0, in the same lane, facing it.
    x, y, yaw = float(front.fleet.x[0]), float(front.fleet.y[0]), float(front.fleet.yaw[0])
    behind.put(0, x - 0.6 * math.cos(yaw), y - 0.6 * math.sin(yaw), yaw)
    for rivals in race.rivals:
        rivals.follow()
    alone = TrackSimulation(track, 1)
    alone.put(0, float(behind.fleet.x[0]), float(behind.fleet.y[0]), yaw)
    lidar = Observer(behind, ("lidar",)).observe()
    lidar_alone = Observer(alone, ("lidar",)).observe()
    ahead = lidar.shape[1] // 2  # the middle ray points straight ahead
    assert lidar[0][ahead] < 0.5 < lidar_alone[0][ahead]
    camera = Observer(behind, ("camera",)).observe()
    camera_alone = Observer(alone, ("camera",)).observe()
    assert not np.array_equal(camera[0], camera_alone[0])  # the car ahead is drawn
    params = behind.all_params()[0]
    assert params["objects_location"] == [[pytest.approx(x), pytest.approx(y)]]
    assert params["closest_objects"] == [0, 0]
    assert front.all_params()[0]["objects_location"][0][0] == pytest.approx(
        float(behind.fleet.x[0])
    )


def test_a_race_takes_two_to_six_cars(track: Track) -> None:
    driver = reference_driver(track)
    for count in (1, 7):
        with pytest.raises(HeadToHeadError, match="2 to 6 cars"):
            HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver)] * count)


def test_without_a_lap_count_the_window_decides_most_laps_then_best_lap(track: Track) -> None:
    race = _race(track, 2, replace(HEAD_TO_HEAD_RULES, lap_count=None, window_seconds=30.0))
    assert race.clock == pytest.approx(30.0)
    assert all(finish.finished_at is None for finish in race.cars)
    laps = [finish.laps_completed for finish in race.cars]
    assert laps == sorted(laps, reverse=True) and laps[0] >= 4
    if laps[0] == laps[1]:
        best = [finish.result.best_lap for finish in race.cars]
        assert best[0] is not None and best[1] is not None
        assert best[0].time_seconds <= best[1].time_seconds


def test_the_race_ends_when_the_first_car_completes_one_lap(track: Track) -> None:
    race = _race(track, 3, replace(HEAD_TO_HEAD_RULES, lap_count=1))
    assert race.winner.laps_completed == 1
    assert [finish.laps_completed for finish in race.cars[1:]] == [0, 0]
    assert race.clock < 10.0


def test_only_a_car_that_drove_past_another_overtook_it(track: Track) -> None:
    """A change of order because a car was put back behind another, or while the car now
    in front stood held, is no overtake: two untrained cars put back in turn swapped
    places step after step, and the race view listed every swap."""
    driver = reference_driver(track)
    race = HeadToHeadRace(track, HEAD_TO_HEAD_RULES, [Entry("a", driver), Entry("b", driver)])
    front, back = race.cars

    def swap(front_status: int, back_status: int) -> list[tuple[str, int, int]]:
        race._order = [0, 1]
        race.grid.standing = np.array([1.0, 2.0])  # car 1 is ahead now
        front.status, back.status = front_status, back_status
        seen = len(race.incidents)
        race._note_overtakes()
        return [(i.kind, i.car, i.other) for i in race.incidents[seen:]]

    assert swap(IN_PROGRESS, IN_PROGRESS) == [("overtake", 1, 0)]
    assert swap(IN_PROGRESS, PAUSE) == []  # the car now in front stood held
    assert swap(OFF_TRACK, IN_PROGRESS) == []  # the other was put back behind it
    assert swap(REVERSED, IN_PROGRESS) == []
    assert swap(IN_PROGRESS, LAP_COMPLETE) == [("overtake", 1, 0)]

"""Boxes in the simulation: each car's own, a crash as DeepRacer judges it, and the reward
params' object keys as simapp computes them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.objects.settings import Lane, ObstacleSettings, RaceSettings, RaceType
from sim.physics.simulation import TrackSimulation
from sim.tracks.catalog import resolve_track

TRACK = "reinvent_base"
# Two boxes on the first straight of re:Invent 2018: one in the inner lane, one in the outer.
FIXED = ObstacleSettings(positions=((0.15, Lane.INNER), (0.02, Lane.OUTER)))


def boxes(settings: ObstacleSettings) -> RaceSettings:
    return RaceSettings(RaceType.OBJECT_AVOIDANCE, obstacles=settings)


def drive_straight(sim: TrackSimulation, steps: int, speed: float = 1.0) -> None:
    for _ in range(steps):
        sim.apply(np.zeros(sim.n), np.full(sim.n, speed))
        if sim.done.all():
            return


def test_driving_into_a_box_is_a_crash_and_the_other_lane_is_clear() -> None:
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 2, race=boxes(ObstacleSettings(positions=((0.1, Lane.INNER),))))
    box = sim.objects
    assert box is not None
    start = 0.1 * box.length - 0.8  # 0.8 m before the box, along the centre line
    sim.reset_cars([0, 1], [start, start])
    # Car 0 drives the inner lane, straight at the box; car 1 the outer lane, past it.
    for car, lane_offset in ((0, 1.0), (1, -1.0)):
        sim.place(car, start, offset=lane_offset * float(sim.track_width[car]) / 4)
    drive_straight(sim, 30)
    assert sim.status[0] == EpisodeStatus.CRASHED
    assert sim.status[1] == EpisodeStatus.IN_PROGRESS
    params = sim.all_params()
    assert params[1]["is_crashed"] is False


def test_object_params_are_simapps() -> None:
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=boxes(FIXED))
    sim.reset_car(0, 0.08 * track.length)  # between the two boxes, over 1 m from each
    params = sim.all_params()[0]
    inner, outer = 0.15 * track.length, 0.02 * track.length
    assert params["objects_distance"] == pytest.approx([inner, outer], abs=0.02)
    # [behind, ahead] of the car's look-ahead point, as indices into the unsorted lists.
    assert params["closest_objects"] == [1, 0]
    assert params["objects_left_of_center"] == [True, False]  # re:Invent 2018 turns left
    width = float(sim.track_width[0])
    assert params["objects_distance_from_center"] == pytest.approx([width / 4] * 2, rel=0.2)
    assert params["objects_speed"] == [0.0, 0.0] and params["objects_heading"] == [0.0, 0.0]
    (x, y), _ = params["objects_location"]
    assert math.hypot(x - params["x"], y - params["y"]) < 2.0
    assert params["object_in_camera"] is True  # the next box is ahead, a little to the left
    sim.reset_car(0, 0.5 * track.length)  # past both: the next one wraps round the lap
    assert sim.all_params()[0]["closest_objects"] == [0, 1]
    assert sim.all_params()[0]["object_in_camera"] is False


def test_each_car_has_its_own_boxes_and_randomised_ones_move_every_episode() -> None:
    settings = ObstacleSettings(count=3, randomize=True)
    sim = TrackSimulation(resolve_track(TRACK), 2, race=boxes(settings), seed=4)
    sim.reset_all()
    field = sim.objects
    assert field is not None
    first = field.distance.copy()
    assert not np.allclose(first[0], first[1])  # two cars, two draws
    sim.reset_car(0)
    assert not np.allclose(field.distance[0], first[0])  # a new episode, new boxes
    assert np.allclose(field.distance[1], first[1])  # the other car's episode goes on
    fixed = TrackSimulation(resolve_track(TRACK), 1, race=boxes(FIXED))
    before = fixed.objects.distance.copy() if fixed.objects is not None else None
    fixed.reset_car(0)
    fixed.reset_car(0)
    assert fixed.objects is not None and np.array_equal(fixed.objects.distance, before)


def test_a_time_trial_has_no_object_keys_filled() -> None:
    sim = TrackSimulation(resolve_track(TRACK), 1)
    sim.reset_car(0)
    params = sim.all_params()[0]
    assert sim.objects is None and params["objects_location"] == []
    assert params["closest_objects"] == [0, 0]


def test_one_car_crashes_into_a_box_as_a_fleet_car_does() -> None:
    # One car takes the simulation's plain-float path (races): the same judgement.
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=boxes(ObstacleSettings(positions=((0.1, Lane.INNER),))))
    start = 0.1 * track.length - 0.8
    sim.reset_car(0, start)
    sim.place(0, start, offset=float(sim.track_width[0]) / 4)
    drive_straight(sim, 30)
    assert sim.status[0] == EpisodeStatus.CRASHED
    assert sim.all_params()[0]["is_crashed"] is True


def test_the_lidar_sees_a_cars_own_boxes() -> None:
    from sim.sensors.observations import Observer

    track = resolve_track(TRACK)
    settings = ObstacleSettings(positions=((0.1, Lane.INNER),))
    with_box = TrackSimulation(track, 2, race=boxes(settings))
    without = TrackSimulation(track, 2)
    start = 0.1 * track.length - 0.8
    for sim in (with_box, without):
        sim.reset_cars([0, 1], [start, start])
        for car in (0, 1):  # in the box's lane, 0.8 m before its centre
            sim.place(car, start, offset=float(sim.track_width[car]) / 4)
    seen = Observer(with_box, ("lidar",)).observe()
    clear = Observer(without, ("lidar",)).observe()
    ahead = seen.shape[1] // 2  # a full circle's middle ray points straight ahead
    # The box's near face is 0.8 - 0.2 = 0.6 m ahead of the car's centre.
    assert float(seen[0, ahead]) == pytest.approx(0.6, abs=0.03)
    assert float(clear[0, ahead]) > 1.0
    behind = 0
    assert float(seen[0, behind]) == pytest.approx(float(clear[0, behind]), abs=1e-5)
    field = with_box.objects
    assert field is not None
    # Only the car's own boxes: a car without boxes here sees past the spot.
    field.x[1], field.y[1] = 100.0, 100.0
    again = Observer(with_box, ("lidar",)).observe()
    assert float(again[1, ahead]) > 1.0 and float(again[0, ahead]) < 0.7


def test_a_car_starting_by_a_box_starts_in_the_other_lane() -> None:
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=boxes(ObstacleSettings(positions=((0.1, Lane.INNER),))))
    box = sim.objects
    assert box is not None
    sim.reset_car(0, float(box.distance[0, 0]) - 0.3)  # 0.3 m before the box
    sim.apply(np.zeros(1), np.full(1, 1.0))
    assert sim.status[0] == EpisodeStatus.IN_PROGRESS  # not started inside or against it
    assert sim.all_params()[0]["is_left_of_center"] is False  # the outer lane: right of centre


def test_trials_meet_the_boxes_and_a_crash_ends_a_training_trial() -> None:
    from sim.race.driver import ReferenceRaceDriver
    from sim.training.evaluation import run_trials

    track = resolve_track(TRACK)
    wall = ObstacleSettings(positions=((0.3, Lane.INNER), (0.3, Lane.OUTER)))  # a wall
    results = run_trials(ReferenceRaceDriver(track), track, 2, race=boxes(wall))
    assert all(result.status == EpisodeStatus.CRASHED for result in results)
    assert all(25.0 < result.progress < 35.0 for result in results)
    clear = run_trials(ReferenceRaceDriver(track), track, 2)
    assert all(result.status == EpisodeStatus.LAP_COMPLETE for result in clear)


def test_an_evaluation_puts_a_car_that_hit_a_box_behind_it_in_the_other_lane() -> None:
    from sim.training.trial_resets import EVALUATION_RESETS, TrialResets

    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=boxes(ObstacleSettings(positions=((0.1, Lane.INNER),))))
    box = sim.objects
    assert box is not None
    start = float(box.distance[0, 0]) - 0.8
    sim.reset_car(0, start)
    sim.place(0, start, offset=float(sim.track_width[0]) / 4)  # in the box's lane
    resets = TrialResets(track, 1, EVALUATION_RESETS)
    for _ in range(30):
        resets.before_step(sim)
        sim.apply(np.zeros(1), np.full(1, 1.0))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.CRASHED
    assert resets.put_back(sim, 0, sim.status[0])
    assert resets.penalty[0] == 5.0  # DeepRacer's COLLISION_PENALTY
    params = sim.all_params()[0]
    # 1 m behind the box along the track, in the outer lane (right of the centre line).
    assert params["is_left_of_center"] is False
    behind = (float(box.distance[0, 0]) - float(sim.s[0])) % track.length
    assert behind == pytest.approx(1.0 - 0.14, abs=0.1)  # params measure 0.14 m ahead
    sim.apply(np.zeros(1), np.full(1, 1.0))
    assert sim.status[0] == EpisodeStatus.IN_PROGRESS  # clear of the box, driving on

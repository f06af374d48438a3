"""The simulator measures and ends episodes the way DeepRacer's simulator (simapp) does.

The oracle here computes the reward params with shapely, the way simapp's
`markov/agent_ctrl/utils.py` and `markov/track_geom/track_data.py` do: project the look-ahead
point on the centre ring, measure the road across at the centre-line point, bisect the
waypoints' distances for [previous, next].
"""

from __future__ import annotations

import bisect
import math

import numpy as np
import pytest
from shapely.geometry import LinearRing, Point

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.simulation import LOOK_AHEAD, EpisodeRules, TrackSimulation
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track
from tests.sim.shapes import rectangle_track


def _simapp_params(track: Track, x: float, y: float) -> dict[str, object]:
    """What simapp hands the reward function for a look-ahead point at (x, y)."""
    centre = LinearRing(track.center)
    inner, outer = LinearRing(track.inner), LinearRing(track.outer)
    point = Point(x, y)
    ndist = centre.project(point, normalized=True)
    foot = centre.interpolate(ndist, normalized=True)
    near_in = inner.interpolate(inner.project(foot))
    near_out = outer.interpolate(outer.project(foot))
    ndists = [centre.project(Point(p), normalized=True) for p in track.center[:-1]]
    ndists.append(1.0)
    following = bisect.bisect_right(ndists, ndist)
    previous = following - 1 if following > 0 else len(ndists) - 1
    following = following if following < len(ndists) else 0
    return {
        "distance_from_center": foot.distance(point),
        "track_width": near_in.distance(near_out),
        "projection_distance": ndist * centre.length,
        "closest_waypoints": [previous, following],
    }


@pytest.mark.parametrize("name", ["hairpin-circuit", "grand-prix"])
def test_params_match_simapp_geometry_at_random_poses(name: str) -> None:
    track = resolve_track(name)
    sim = TrackSimulation(track, 1)
    sim.reset_car(0, start_s=0.0)
    rng = np.random.default_rng(7)
    centre = track.centerline
    for s in rng.uniform(0.0, track.length, size=40):
        point = centre.point_at(np.array([s]))[0]
        tangent = centre.direction_at(np.array([s]))[0]
        offset = rng.uniform(-0.2, 0.2)
        yaw = math.atan2(tangent[1], tangent[0]) + rng.uniform(-0.4, 0.4)
        x, y = point[0] - offset * tangent[1], point[1] + offset * tangent[0]
        sim.put(0, float(x), float(y), yaw)
        params = sim.all_params()[0]
        assert params["x"] == pytest.approx(x + LOOK_AHEAD * math.cos(yaw))
        assert params["y"] == pytest.approx(y + LOOK_AHEAD * math.sin(yaw))
        expected = _simapp_params(track, params["x"], params["y"])
        for key in ("distance_from_center", "track_width", "projection_distance"):
            assert params[key] == pytest.approx(expected[key], abs=1e-6), key
        assert params["closest_waypoints"] == expected["closest_waypoints"]


@pytest.mark.parametrize(
    ("ahead", "expected"),
    [
        ((2.0, 0.1), [4, 5]),  # exactly abreast of waypoint 4 (2.0, 0.0): it is the previous
        ((1.99, 0.1), [3, 4]),
        ((0.0, -0.1), [0, 1]),  # on the start line: the first waypoint, not the closing one
        ((-0.01, 0.5), [39, 40]),
    ],
)
def test_closest_waypoints_break_ties_at_a_waypoint_as_simapp(
    ahead: tuple[float, float], expected: list[int]
) -> None:
    track = rectangle_track()
    sim = TrackSimulation(track, 1)
    sim.reset_car(0, start_s=1.0)
    yaw = math.pi / 2 if ahead[0] < 0 else 0.0
    sim.put(0, ahead[0] - LOOK_AHEAD * math.cos(yaw), ahead[1] - LOOK_AHEAD * math.sin(yaw), yaw)
    params = sim.all_params()[0]
    assert params["closest_waypoints"] == expected
    assert params["closest_waypoints"] == _simapp_params(track, *ahead)["closest_waypoints"]


@pytest.mark.parametrize("cars", [1, 3])
def test_an_episode_starts_a_look_ahead_into_its_lap(cars: int) -> None:
    # DeepRacer's console sim-trace of re:Invent 2018 (17.71 m) starts at 0.79 % progress:
    # progress counts from the car centre's start, measured at the point 0.14 m ahead.
    sim = TrackSimulation(rectangle_track(), cars)
    sim.reset_cars(range(cars), [2.0] * cars)
    for params in sim.all_params():
        assert params["progress"] == pytest.approx(LOOK_AHEAD / 20.0 * 100.0)
    assert sim.progress[0] == pytest.approx(0.7)


def test_backing_over_the_start_gives_negative_progress_to_the_reward_function() -> None:
    sim = TrackSimulation(rectangle_track(), 1)
    sim.reset_car(0, start_s=2.0)
    sim.put(0, 2.0, 0.0, math.pi)  # turned round on the start position
    for _ in range(8):
        sim.apply(np.array([0.0]), np.array([1.0]))
    params = sim.all_params()[0]
    # simapp's compute_current_prog: not wrapped to 99 %, not clipped at 0.
    assert -5.0 < params["progress"] < 0.0
    assert sim.progress[0] == 0.0  # what metrics and charts show


@pytest.mark.parametrize("cars", [1, 2])
def test_a_lap_completed_in_the_step_that_leaves_the_track_counts_as_a_lap(cars: int) -> None:
    sim = TrackSimulation(rectangle_track(), cars)
    sim.reset_cars(range(cars), [0.0] * cars)
    for car in range(cars):
        # Coming down the left side to the line, already over the infield, 3 cm short of
        # a lap: the next step does both.
        sim.put(car, 0.6, 0.9, -math.pi / 2, speed=1.0)
        sim.continue_episode(car, 20.0 - 0.03)
    sim.apply(np.zeros(cars), np.ones(cars))
    assert sim.offtrack.all()
    assert list(sim.status) == [EpisodeStatus.LAP_COMPLETE] * cars
    assert sim.all_params()[0]["progress"] == 100.0


def test_a_crash_and_an_off_track_in_one_step_is_a_crash() -> None:
    sim = TrackSimulation(rectangle_track(), 2)
    sim.reset_cars(range(2), [3.0, 3.0])
    sim.put(0, 3.0, 0.7, 0.0)  # off the road
    sim.fleet.crashed[0] = True
    sim._judge()
    assert sim.status[0] == EpisodeStatus.CRASHED


# --- start positions and driving direction -------------------------------------------------
def _start_xy(sim: TrackSimulation, car: int) -> tuple[float, float]:
    return round(float(sim.fleet.x[car]), 6), round(float(sim.fleet.y[car]), 6)


def test_change_start_position_moves_each_episode_round_the_track() -> None:
    sim = TrackSimulation(rectangle_track(), 2)
    sim.reset_all()
    first = sim.start_s[0]
    sim.reset_car(0)
    assert sim.start_s[0] == pytest.approx(first + 0.05 * 20.0)
    assert sim.start_s[1] == pytest.approx(10.0)  # the fleet is spread round the track


def test_without_change_start_position_every_episode_starts_on_the_line() -> None:
    sim = TrackSimulation(rectangle_track(), 3, rules=EpisodeRules(change_start=False))
    sim.reset_all()
    starts = {_start_xy(sim, car) for car in range(3)}
    for _ in range(3):
        sim.reset_car(1)
        starts.add(_start_xy(sim, 1))
    assert starts == {(0.0, 0.0)}


def test_alternate_driving_direction_turns_each_car_round_every_episode() -> None:
    track = rectangle_track()
    rules = EpisodeRules(alternate_direction=True, change_start=False)
    sim = TrackSimulation(track, 2, rules=rules)
    sim.reset_all()
    seen = []
    for _ in range(4):
        params = sim.all_params()[0]
        seen.append(params["is_reversed"])
        # From the line the rectangle goes right (+x); the other way round it goes up (+y).
        assert params["heading"] == pytest.approx(90.0 if params["is_reversed"] else 0.0)
        sim.reset_car(0)
    assert seen == [False, True, False, True]
    assert sim.all_params()[1]["is_reversed"] is True  # the fleet trains both ways at once


def test_a_car_driving_the_other_way_sees_the_track_its_way_round() -> None:
    track = rectangle_track()
    rules = EpisodeRules(alternate_direction=True, change_start=False)
    sim = TrackSimulation(track, 2, rules=rules)
    sim.reset_all()
    for _ in range(15):
        sim.apply(np.zeros(2), np.ones(2))
    forward, backward = sim.all_params()
    assert [sim.status[0], sim.status[1]] == [EpisodeStatus.IN_PROGRESS] * 2
    # Both drove about a metre from the line, each its own way: equal progress.
    assert backward["progress"] == pytest.approx(forward["progress"], abs=0.2)
    assert forward["progress"] > 4.0
    assert backward["waypoints"] == track.waypoints[::-1]
    assert backward["y"] > 0.9 and forward["x"] > 0.9
    assert backward["projection_distance"] == pytest.approx(backward["y"])
    expected = _simapp_params(track.reversed(), backward["x"], backward["y"])
    assert backward["closest_waypoints"] == expected["closest_waypoints"]
    # Left of centre is the infield for both: the rectangle's inside is on the left going
    # counter-clockwise, on the right going clockwise.
    sim.put(0, 3.0, 0.2, 0.0)
    sim.put(1, 3.0, 0.2, math.pi)
    assert [p["is_left_of_center"] for p in sim.all_params()] == [True, False]
    sim.put(1, 3.0, -0.2, math.pi)
    assert sim.all_params()[1]["is_left_of_center"] is True


def test_a_reversed_track_is_driven_against_its_row_order() -> None:
    track = rectangle_track()
    sim = TrackSimulation(track, 1, is_reversed=True)
    sim.reset_car(0, start_s=0.0)
    for _ in range(15):
        sim.apply(np.zeros(1), np.ones(1))
    params = sim.all_params()[0]
    assert sim.status[0] == EpisodeStatus.IN_PROGRESS
    assert params["is_reversed"] is True
    assert params["waypoints"] == track.waypoints[::-1]
    assert params["y"] > 0.5  # went up the left side: clockwise round the rectangle
    assert params["progress"] > 4.0


@pytest.mark.parametrize("cars", [1, 2])
def test_a_car_turned_round_sees_what_a_car_on_the_reversed_track_sees(cars: int) -> None:
    from sim.sensors.observations import vector_state

    track = resolve_track("hairpin-circuit")
    rules = EpisodeRules(alternate_direction=True, change_start=False)
    turned = TrackSimulation(track, cars, rules=rules)
    turned.reset_all()
    if cars == 1:
        turned.reset_car(0)  # its second episode, turned round
    car = cars - 1  # with two cars, car 1 starts turned round
    reversed_track = TrackSimulation(track, 1, is_reversed=True)
    reversed_track.reset_car(0, start_s=0.0)
    turn = float(turned.fleet.yaw[car] - reversed_track.fleet.yaw[0])
    assert math.remainder(turn, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    for step in range(40):
        steering = 10.0 * math.sin(step / 6.0)
        turned.apply(np.full(cars, steering), np.full(cars, 1.5))
        reversed_track.apply(np.array([steering]), np.array([1.5]))
        mine, theirs = turned.all_params()[car], reversed_track.all_params()[0]
        measured = ("x", "y", "heading", "progress", "distance_from_center", "projection_distance")
        for key in measured:
            assert mine[key] == pytest.approx(theirs[key], abs=1e-6), key
        for key in ("closest_waypoints", "is_left_of_center", "is_reversed", "waypoints"):
            assert mine[key] == theirs[key], key
        np.testing.assert_allclose(
            vector_state(turned)[car], vector_state(reversed_track)[0], atol=1e-4
        )

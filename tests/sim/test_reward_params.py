"""DeepRacer reward params checked against hand-computed geometry on a rectangle track."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.simulation import LOOK_AHEAD, EpisodeRules, TrackSimulation
from sim.reward.sample_params import PARAM_KEYS
from tests.sim.shapes import rectangle_track


@pytest.fixture
def sim() -> TrackSimulation:
    simulation = TrackSimulation(rectangle_track(), 1)
    simulation.reset_car(0, start_s=0.0)
    return simulation


def test_every_deepracer_key_is_present(sim: TrackSimulation) -> None:
    params = sim.all_params()[0]
    assert set(params) == set(PARAM_KEYS)
    assert params["closest_objects"] == [0, 0]
    assert params["objects_location"] == []
    assert params["object_in_camera"] is False


def test_position_is_the_point_ahead_of_the_car_centre(sim: TrackSimulation) -> None:
    sim.put(0, 2.0, 0.1, 0.0)
    params = sim.all_params()[0]
    assert params["x"] == pytest.approx(2.0 + LOOK_AHEAD)
    assert params["y"] == pytest.approx(0.1)
    assert params["distance_from_center"] == pytest.approx(0.1)
    assert params["is_left_of_center"] is True
    # Nearest inner border point (2.14, 0.38), nearest outer (2.14, -0.38).
    assert params["track_width"] == pytest.approx(0.76)
    # Waypoints every 0.5 m along the bottom side: 2.14 lies between #4 (2.0) and #5 (2.5).
    assert params["closest_waypoints"] == [4, 5]
    assert params["projection_distance"] == pytest.approx(2.14)
    assert params["track_length"] == pytest.approx(20.0)
    assert params["waypoints"][5] == (2.5, 0.0)
    assert params["all_wheels_on_track"] is True
    assert params["is_offtrack"] is False


def test_right_of_centre_on_the_right_hand_side(sim: TrackSimulation) -> None:
    # Going up the right side (+y): left of the centre line is -x (towards the infield).
    sim.put(0, 6.2, 1.0, math.pi / 2)
    params = sim.all_params()[0]
    assert params["is_left_of_center"] is False
    assert params["distance_from_center"] == pytest.approx(0.2)
    assert params["heading"] == pytest.approx(90.0)
    assert params["projection_distance"] == pytest.approx(6.0 + 1.0 + LOOK_AHEAD)


@pytest.mark.parametrize(
    ("yaw_deg", "expected"),
    [(0.0, 0.0), (179.0, 179.0), (181.0, -179.0), (-90.0, -90.0), (540.0, 180.0)],
)
def test_heading_is_degrees_in_minus_180_to_180(
    sim: TrackSimulation, yaw_deg: float, expected: float
) -> None:
    sim.put(0, 2.0, 0.0, math.radians(yaw_deg))
    assert sim.all_params()[0]["heading"] == pytest.approx(expected)


def test_one_wheel_off_is_not_all_wheels_on_track_but_not_offtrack(sim: TrackSimulation) -> None:
    # Left wheels at y = 0.40 + 0.08 = 0.48 are past the inner border (0.38); right at 0.32.
    sim.put(0, 2.0, 0.40, 0.0)
    params = sim.all_params()[0]
    assert params["all_wheels_on_track"] is False
    assert params["is_offtrack"] is False


def test_all_four_wheels_off_is_offtrack(sim: TrackSimulation) -> None:
    sim.put(0, 2.0, 0.60, 0.0)
    params = sim.all_params()[0]
    assert params["all_wheels_on_track"] is False
    assert params["is_offtrack"] is True


def test_progress_counts_from_the_episode_start_and_steps_from_one() -> None:
    sim = TrackSimulation(rectangle_track(), 1)
    sim.reset_car(0, start_s=1.0)  # car centre at x = 1.0: the look-ahead point at 1.14
    for _ in range(15):
        sim.apply(np.array([0.0]), np.array([1.0]))
    params = sim.all_params()[0]
    # As in DeepRacer, from where the car centre started to where the look-ahead point is.
    travelled = params["x"] - 1.0
    assert travelled > 0.3 + LOOK_AHEAD
    assert params["progress"] == pytest.approx(travelled / 20.0 * 100.0)
    assert params["steps"] == 15
    assert params["sim_time"] == pytest.approx(1.0)
    assert params["speed"] == 1.0
    assert params["steering_angle"] == 0.0


def test_driving_straight_off_the_track_ends_the_episode_off_track() -> None:
    sim = TrackSimulation(rectangle_track(), 1)
    sim.reset_car(0, start_s=4.0)
    for _ in range(60):
        sim.apply(np.array([0.0]), np.array([2.0]))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.OFF_TRACK
    assert sim.all_params()[0]["is_offtrack"] is True


def test_reversing_round_the_track_is_detected() -> None:
    sim = TrackSimulation(rectangle_track(), 1)
    sim.reset_car(0, start_s=3.0)
    sim.put(0, 3.0, 0.0, math.pi)  # facing against the driving direction
    for _ in range(40):
        sim.apply(np.array([0.0]), np.array([0.5]))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.REVERSED
    assert sim.steps[0] == 15


def test_hitting_a_box_is_a_crash() -> None:
    sim = TrackSimulation(rectangle_track(), 1)
    sim.reset_car(0, start_s=3.0)
    sim.fleet.add_box(3.0 + 0.162 + 0.01 + 0.15, 0.0, 0.0, 0.3, 0.3)  # a box right ahead
    for _ in range(60):
        sim.apply(np.array([0.0]), np.array([0.5]))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.CRASHED
    assert sim.all_params()[0]["is_crashed"] is True
    assert sim.fleet.x[0] < 3.0 + 0.3  # the box stopped it


def test_a_car_that_barely_moves_is_immobilized() -> None:
    # At 0.1 m/s a step covers ~6.7 mm; with a 1 cm threshold that counts as not moving.
    sim = TrackSimulation(rectangle_track(), 1, rules=EpisodeRules(immobile_distance=0.01))
    sim.reset_car(0, start_s=3.0)
    for _ in range(40):
        sim.apply(np.array([0.0]), np.array([0.1]))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.IMMOBILIZED


def test_a_completed_lap_ends_at_progress_100() -> None:
    from sim.physics.reference_driver import ReferenceDriver
    from tests.sim.shapes import ring_track

    track = ring_track()
    sim = TrackSimulation(track, 1)
    driver = ReferenceDriver(track)
    sim.reset_car(0, start_s=0.0)
    for _ in range(15 * 60):
        sim.apply(*driver.act(sim))
        if sim.status[0] != EpisodeStatus.IN_PROGRESS:
            break
    assert sim.status[0] == EpisodeStatus.LAP_COMPLETE
    assert sim.all_params()[0]["progress"] == 100.0

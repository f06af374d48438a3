"""Object avoidance's settings as training_params.yaml holds them, and where its boxes
stand, with DeepRacer's keys, defaults and placement rules (docs/deepracer-objects.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.deepracer.files import DeepRacerFileError, TrainingParams, parse_training_params
from sim.physics.objects.placement import (
    CLEAR_BEFORE_LINE,
    Lanes,
    obstacle_distances,
    obstacle_poses,
)
from sim.physics.objects.reading import race_settings
from sim.physics.objects.settings import Lane, ObstacleSettings, RaceType
from sim.tracks.catalog import resolve_track


def settings_of(yaml_text: str):  # type: ignore[no-untyped-def]
    return race_settings(parse_training_params(yaml_text, "training_params.yaml"))


def test_a_time_trial_has_no_objects_and_keys_of_other_types_do_not_apply() -> None:
    settings = race_settings(TrainingParams("reinvent_base", extra={"NUMBER_OF_OBSTACLES": 3}))
    assert settings.race_type is RaceType.TIME_TRIAL
    assert settings.obstacles.boxes == 0 and settings.bots.count == 0


def test_object_avoidance_reads_deepracers_keys_and_defaults() -> None:
    settings = settings_of(
        "WORLD_NAME: reinvent_base\nRACE_TYPE: OBJECT_AVOIDANCE\nNUMBER_OF_OBSTACLES: 3\n"
        'RANDOMIZE_OBSTACLE_LOCATIONS: "true"\n'
    )
    assert settings.race_type is RaceType.OBJECT_AVOIDANCE
    obstacles = settings.obstacles
    assert (obstacles.count, obstacles.randomize, obstacles.min_distance_percent) == (3, True, 2.0)
    assert obstacles.obstacle_type == "box_obstacle" and not obstacles.bot_car
    fixed = settings_of(
        "WORLD_NAME: reinvent_base\nRACE_TYPE: object_avoidance\n"
        'OBJECT_POSITIONS: ["0.25,1", "0.5,-1"]\n'
    ).obstacles
    assert fixed.positions == ((0.25, Lane.INNER), (0.5, Lane.OUTER)) and fixed.boxes == 2


def test_head_to_bot_reads_deepracers_keys_and_defaults() -> None:
    bots = settings_of(
        "WORLD_NAME: reinvent_base\nRACE_TYPE: HEAD_TO_BOT\nNUMBER_OF_BOT_CARS: 3\n"
        "IS_LANE_CHANGE: true\n"
    ).bots
    assert (bots.count, bots.speed, bots.lane_change) == (3, 0.2, True)
    assert (bots.lower_lane_change_time, bots.upper_lane_change_time) == (3.0, 5.0)
    assert (bots.lane_change_distance, bots.penalty_seconds, bots.min_distance) == (1.0, 2.0, 2.0)


@pytest.mark.parametrize(
    ("lines", "said"),
    [
        ("RACE_TYPE: DRAG_RACE", "RACE_TYPE must be one of TIME_TRIAL"),
        ("RACE_TYPE: OBJECT_AVOIDANCE", "needs NUMBER_OF_OBSTACLES from 1 to 10"),
        ("RACE_TYPE: OBJECT_AVOIDANCE\nNUMBER_OF_OBSTACLES: 40", "NUMBER_OF_OBSTACLES must be"),
        ('RACE_TYPE: OBJECT_AVOIDANCE\nOBJECT_POSITIONS: ["1.5,1"]', "progress from 0 to 1"),
        ('RACE_TYPE: OBJECT_AVOIDANCE\nOBJECT_POSITIONS: ["0.5,2"]', "lane 1 (inner) or -1"),
        (
            "RACE_TYPE: OBJECT_AVOIDANCE\nNUMBER_OF_OBSTACLES: 2\nOBSTACLE_TYPE: bomb",
            "OBSTACLE_TYPE",
        ),
        ("RACE_TYPE: HEAD_TO_BOT\nNUMBER_OF_BOT_CARS: 2\nBOT_CAR_SPEED: fast", "BOT_CAR_SPEED"),
        (
            "RACE_TYPE: HEAD_TO_BOT\nNUMBER_OF_BOT_CARS: 2\nLOWER_LANE_CHANGE_TIME: 6",
            "must not be below LOWER_LANE_CHANGE_TIME",
        ),
        ("RACE_TYPE: HEAD_TO_BOT\nNUMBER_OF_BOT_CARS: 2\nIS_LANE_CHANGE: maybe", "true or false"),
    ],
)
def test_a_bad_setting_is_one_sentence_naming_its_key(lines: str, said: str) -> None:
    with pytest.raises(DeepRacerFileError) as caught:
        settings_of(f"WORLD_NAME: reinvent_base\n{lines}\n")
    message = str(caught.value)
    assert said in message and message.startswith("training_params.yaml: ")
    assert message.count(". ") == 0 and message.endswith(".")


def test_fixed_boxes_stand_in_the_middle_of_their_lane_facing_along_it() -> None:
    track = resolve_track("reinvent_base")
    lanes = Lanes.of(track)
    settings = ObstacleSettings(positions=((0.25, Lane.INNER), (0.5, Lane.OUTER)))
    inner, outer = obstacle_poses(settings, lanes, np.random.default_rng(0))
    length = lanes.centre.total_length
    assert inner.distance == pytest.approx(0.25 * length) and outer.lane is Lane.OUTER
    for pose, own, other in ((inner, track.inner, track.outer), (outer, track.outer, track.inner)):
        point = np.array([[pose.x, pose.y]])
        to_own = np.min(np.hypot(*(own - point).T))
        to_other = np.min(np.hypot(*(other - point).T))
        width = to_own + to_other
        assert to_own == pytest.approx(width / 4, rel=0.15)  # a quarter of the road from its side
        tangent = lanes.centre.direction_at(np.array([pose.distance]))[0]
        assert math.cos(pose.heading) * tangent[0] + math.sin(pose.heading) * tangent[1] > 0.9


def test_boxes_not_randomised_are_evenly_spaced_in_alternate_lanes() -> None:
    lanes = Lanes.of(resolve_track("reinvent_base"))
    length = lanes.centre.total_length
    poses = obstacle_poses(ObstacleSettings(count=3), lanes, np.random.default_rng(0))
    distances = [pose.distance for pose in poses]
    assert distances == pytest.approx(np.linspace(0.02 * length, length - 1.0, 3))
    assert [pose.lane for pose in poses] == [Lane.INNER, Lane.OUTER, Lane.INNER]


def test_randomised_boxes_move_every_episode_and_keep_their_spacing() -> None:
    settings = ObstacleSettings(count=4, randomize=True, min_distance_percent=10.0)
    length = 17.7
    rng = np.random.default_rng(3)
    episodes = [obstacle_distances(settings, length, rng) for _ in range(50)]
    assert len({tuple(np.round(d, 6)) for d in episodes}) == 50  # drawn again each episode
    gap = 0.1 * length
    for distances in episodes:
        assert np.all(np.diff(distances) >= gap - 1e-9)  # in order, the minimum apart
        assert distances[0] >= gap - 1e-9 and distances[-1] <= length - CLEAR_BEFORE_LINE + 1e-9
    # Unlike simapp, whose spacing shrinks at every reset on tracks under 100 m, it holds.
    assert min(np.min(np.diff(d)) for d in episodes[-10:]) >= gap - 1e-9
    again = np.random.default_rng(3)
    assert np.array_equal(obstacle_distances(settings, length, again), episodes[0])

"""ALTERNATE_DRIVING_DIRECTION among objects: simapp reverses the track for the episode, so a
car driving the other way round meets its boxes placed along the reversed lines, its bots
drive its way, and its params measure them its way round."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.objects.field import ObjectField
from sim.physics.objects.settings import BotSettings, Lane, ObstacleSettings, RaceSettings, RaceType
from sim.physics.simulation import EpisodeRules, TrackSimulation
from sim.tracks.catalog import resolve_track

TRACK = resolve_track("reinvent_base")
ALTERNATE = EpisodeRules(alternate_direction=True)


def _boxes(*positions: tuple[float, Lane]) -> RaceSettings:
    return RaceSettings(RaceType.OBJECT_AVOIDANCE, obstacles=ObstacleSettings(positions=positions))


def _started(race: RaceSettings, cars: int = 2) -> tuple[TrackSimulation, ObjectField]:
    """`cars` cars among `race`'s objects, each started (odd cars the other way round)."""
    sim = TrackSimulation(TRACK, cars, rules=ALTERNATE, race=race)
    sim.reset_all()
    field = sim.objects
    assert field is not None
    return sim, field


def _forward_s(x: float, y: float) -> float:
    """Distance along the track's rows of the centre-line point nearest (x, y)."""
    segment, t, _ = TRACK.centerline.project(np.array([[x, y]]))
    return float(TRACK.centerline.arc_length(segment, t)[0])


def test_boxes_stand_along_the_way_the_car_drives() -> None:
    # Car 1 starts its first episode the other way round (odd cars do, as in training).
    sim, field = _started(_boxes((0.25, Lane.INNER), (0.6, Lane.OUTER)))
    assert sim.reverse.tolist() == [False, True]
    length = TRACK.length
    for car in (0, 1):
        # OBJECT_POSITIONS are progress along the car's own way round.
        assert field.distance[car] == pytest.approx([0.25 * length, 0.6 * length])
    # Physically, the backwards car's box at 25 % of its lap stands at 75 % of the track's.
    s0 = [_forward_s(x, y) for x, y in zip(field.x[0], field.y[0], strict=True)]
    s1 = [_forward_s(x, y) for x, y in zip(field.x[1], field.y[1], strict=True)]
    assert s0 == pytest.approx([0.25 * length, 0.6 * length], abs=0.05)
    assert s1 == pytest.approx([0.75 * length, 0.4 * length], abs=0.05)
    # Its inner lane is still the inner lane, now on the other hand.
    assert field.left[1].tolist() == [not field.left[0, 0], not field.left[0, 1]]


def test_a_backwards_car_measures_its_objects_its_own_way_round() -> None:
    sim, field = _started(_boxes((0.1, Lane.INNER), (0.4, Lane.OUTER), (0.7, Lane.INNER)))
    for _ in range(20):  # both cars drive a little, each its way
        sim.apply(np.zeros(2), np.full(2, 1.0))
    params = sim.all_params()[1]
    assert params["objects_distance"] == pytest.approx(
        [0.1 * TRACK.length, 0.4 * TRACK.length, 0.7 * TRACK.length]
    )
    # The next object is the first one ahead of the car as it drives: found here from the
    # physical positions along the track's rows, where the backwards car's way is down.
    car_s = _forward_s(float(sim.ahead[1, 0]), float(sim.ahead[1, 1]))
    behind_car = [
        (car_s - _forward_s(x, y)) % TRACK.length
        for x, y in zip(field.x[1], field.y[1], strict=True)
    ]
    assert params["closest_objects"][1] == int(np.argmin(behind_car))
    assert params["closest_objects"][0] == int(np.argmax(behind_car))


def test_a_backwards_cars_bots_drive_its_way_round() -> None:
    sim, field = _started(RaceSettings(RaceType.HEAD_TO_BOT, bots=BotSettings(count=2, speed=0.6)))

    def where() -> list[float]:
        return [_forward_s(x, y) for x, y in zip(field.x[1], field.y[1], strict=True)]

    before = where()
    for _ in range(30):  # two seconds
        sim.apply(np.zeros(2), np.zeros(2))
    moved = [(a - b) % TRACK.length for a, b in zip(before, where(), strict=True)]
    assert moved == pytest.approx([1.2, 1.2], abs=0.05)  # down the track's rows
    # Heading along the reversed lanes: against the track's rows.
    for x, y, heading in zip(field.x[1], field.y[1], field.heading[1], strict=True):
        s = _forward_s(x, y)
        tangent = TRACK.centerline.direction_at(np.array([s]))[0]
        assert math.cos(heading - math.atan2(tangent[1], tangent[0])) < -0.95


def test_a_backwards_car_running_into_its_bot_crashes() -> None:
    sim, field = _started(RaceSettings(RaceType.HEAD_TO_BOT, bots=BotSettings(count=1, speed=0.3)))
    x, y, yaw = float(field.x[1, 0]), float(field.y[1, 0]), float(field.heading[1, 0])
    sim.put(1, x - 0.5 * math.cos(yaw), y - 0.5 * math.sin(yaw), yaw)  # behind it, its way
    for _ in range(30):
        sim.apply(np.zeros(2), np.array([0.0, 2.0]))
        if sim.done[1]:
            break
    assert sim.status[1] == EpisodeStatus.CRASHED


def test_a_backwards_car_starts_in_the_other_lane_than_a_box_by_its_start() -> None:
    # Car 1 of 2 starts half a lap round, backwards: a box 0.3 m on from there, its way.
    ahead = 0.5 + 0.3 / TRACK.length
    sim, field = _started(_boxes((ahead, Lane.INNER)))
    assert field.backwards[1]
    x, y = float(sim.fleet.x[1]), float(sim.fleet.y[1])
    gap = abs(_forward_s(x, y) - _forward_s(float(field.x[1, 0]), float(field.y[1, 0])))
    assert gap < 1.0
    _, _, foot = TRACK.centerline.project(np.array([[x, y]]))
    assert math.hypot(x - foot[0, 0], y - foot[0, 1]) > 0.1  # in a lane, not on the centre
    # In the outer lane: the box stands in the inner one.
    inner_is_left = field.inner_is_left(1)
    yaw = float(sim.fleet.yaw[1])
    left = -math.sin(yaw) * (x - foot[0, 0]) + math.cos(yaw) * (y - foot[0, 1]) > 0.0
    assert left != inner_is_left

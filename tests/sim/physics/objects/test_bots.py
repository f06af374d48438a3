"""Head-to-bot: bot cars that drive their lanes at their speed and change lanes as simapp's
do, crashes judged as DeepRacer judges them, and races among boxes and bots."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.objects.settings import BotSettings, RaceSettings, RaceType
from sim.physics.simulation import TrackSimulation
from sim.race.driver import reference_driver
from sim.race.engine import race_ticks, run_race
from sim.race.result import RaceResult
from sim.race.rules import preset_rules
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import run_trials

TRACK = "reinvent_base"


def bots(**settings: object) -> RaceSettings:
    return RaceSettings(RaceType.HEAD_TO_BOT, bots=BotSettings(**settings))  # type: ignore[arg-type]


def stand_still(sim: TrackSimulation, steps: int) -> None:
    for _ in range(steps):
        sim.apply(np.zeros(sim.n), np.zeros(sim.n))


def test_bots_drive_their_lanes_at_their_speed() -> None:
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=bots(count=2, speed=0.6))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    before = field.distance[0].copy()
    stand_still(sim, 30)  # two seconds
    moved = (field.distance[0] - before) % track.length
    assert moved == pytest.approx([1.2, 1.2], abs=0.01)
    # Not randomised, the lanes alternate: the first bot in the inner lane, the next outer;
    # each a quarter of the road from the centre line.
    quarter = [float(np.mean(track.widths)) / 4.0] * 2
    assert field.from_centre[0] == pytest.approx(quarter, abs=0.03)
    inner_is_left = track.direction == "counter-clockwise"
    assert field.left[0].tolist() == [inner_is_left, not inner_is_left]
    params = sim.all_params()[0]
    assert params["objects_speed"] == [0.6, 0.6]
    # Headings in radians along the lane: the bots drive the way the track runs.
    for heading, distance in zip(
        params["objects_heading"], params["objects_distance"], strict=True
    ):
        tangent = sim.centre_projector.direction_at(distance)
        assert math.cos(heading - math.atan2(tangent[1], tangent[0])) > 0.95


def test_a_bot_changes_lanes_after_three_to_five_seconds() -> None:
    sim = TrackSimulation(resolve_track(TRACK), 1, race=bots(count=1, speed=1.0, lane_change=True))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    first_side = bool(field.left[0, 0])
    sides = []
    for _ in range(15 * 7):
        stand_still(sim, 1)
        sides.append(bool(field.left[0, 0]))
    switched = sides.index(not first_side)
    # simapp: U(3, 5) s in its lane, then one second (1 m at 1 m/s) across.
    assert 3.0 <= switched / 15 <= 6.0
    assert all(side != first_side for side in sides[switched + 15 :])


def test_running_into_a_bot_is_a_crash_but_being_run_into_is_not() -> None:
    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=bots(count=1, speed=0.3))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    # Put the car 0.5 m behind the bot, in its lane, and drive into it.
    bot_x, bot_y, bot_yaw = float(field.x[0, 0]), float(field.y[0, 0]), float(field.heading[0, 0])
    back = 0.5
    sim.put(0, bot_x - back * math.cos(bot_yaw), bot_y - back * math.sin(bot_yaw), bot_yaw)
    for _ in range(30):
        sim.apply(np.zeros(1), np.full(1, 2.0))
        if sim.done[0]:
            break
    assert sim.status[0] == EpisodeStatus.CRASHED

    # A car standing in a bot's way is hit from behind: no crash of the car's; the bots
    # stop for their penalty seconds instead.
    sim = TrackSimulation(track, 1, race=bots(count=1, speed=1.0, penalty_seconds=2.0))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    ahead = 0.6
    sim.put(0, bot_x + ahead * math.cos(bot_yaw), bot_y + ahead * math.sin(bot_yaw), bot_yaw)
    stand_still(sim, 15)
    assert sim.status[0] == EpisodeStatus.IN_PROGRESS
    assert field.paused[0] > 0.0
    where = float(field.distance[0, 0])
    stand_still(sim, 10)
    assert float(field.distance[0, 0]) == pytest.approx(where)  # standing still, paused


def test_the_lidar_sees_a_bot_ahead() -> None:
    from sim.sensors.observations import Observer, SensorOptions

    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=bots(count=1, speed=0.0))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    x, y, yaw = float(field.x[0, 0]), float(field.y[0, 0]), float(field.heading[0, 0])
    sim.put(0, x - 1.0 * math.cos(yaw), y - 1.0 * math.sin(yaw), yaw)
    observer = Observer(sim, ("lidar",), SensorOptions(lidar_rays=64))
    scan = observer.observe()[0]
    ahead = int(np.argmin(np.abs(np.cos(observer._lidar.angles) - 1.0)))
    # The ray straight ahead meets the bot's tail, half its length short of 1 m.
    assert float(scan[ahead]) == pytest.approx(1.0 - 0.3235 / 2.0, abs=0.05)


@pytest.mark.parametrize("preset", ["object-avoidance", "head-to-bot"])
def test_the_reference_driver_finishes_laps_among_objects(preset: str) -> None:
    track = resolve_track(TRACK)
    rules = preset_rules(preset)
    result = run_race(track, rules, seed=3)
    assert result.valid_laps >= 10  # a baseline for the race type
    assert result.rules.race_type is not RaceType.TIME_TRIAL
    # The same race again is the same race: objects placed and driven from the seed.
    again = run_race(track, rules, seed=3)
    assert [lap.time_seconds for lap in again.laps] == [lap.time_seconds for lap in result.laps]
    # The result keeps the race type and each lap its crashes through JSON.
    back = RaceResult.from_json(result.to_json())
    assert back.rules == rules
    assert [lap.crashes for lap in back.laps] == [lap.crashes for lap in result.laps]


@pytest.mark.parametrize("preset", ["object-avoidance", "head-to-bot"])
@pytest.mark.parametrize("track_name", [TRACK, "reInvent2019_track"])
def test_the_reference_driver_finishes_every_trial_among_objects(
    preset: str, track_name: str
) -> None:
    # Five cars side by side, each among its own objects; the trials' start jitter is taken
    # from where the car starts (in the other lane than a box by the line), so no trial
    # starts inside a box's crash zone. Before, trials 2-5 among boxes crashed at once.
    track = resolve_track(track_name)
    race = preset_rules(preset).race_settings
    results = run_trials(reference_driver(track), track, 5, race=race, seed=1)
    assert [r.status for r in results] == [str(EpisodeStatus.LAP_COMPLETE)] * 5


def test_a_crash_in_a_race_costs_the_collision_penalty_and_is_counted_in_its_lap() -> None:
    track = resolve_track(TRACK)
    rules = preset_rules("head-to-bot")
    result = run_race(track, rules, seed=0)
    crashed = [lap for lap in result.laps if lap.crashes]
    assert crashed, "the bots caught the reference driver at least once"
    for lap in crashed:
        assert lap.penalty_seconds >= lap.crashes * rules.collision_penalty_seconds - 1e-9


def test_a_live_race_shows_where_the_objects_are() -> None:
    track = resolve_track(TRACK)
    ticks = race_ticks(track, preset_rules("head-to-bot"))
    first = next(ticks)
    for _ in range(30):
        later = next(ticks)
    assert len(first.objects) == 3
    assert later.objects != first.objects  # the bots drove on
    boxes = next(race_ticks(track, preset_rules("object-avoidance")))
    assert len(boxes.objects) == 3


@pytest.mark.parametrize("preset", ["object-avoidance", "head-to-bot"])
def test_a_replay_shows_the_objects_where_the_race_had_them(preset: str) -> None:
    from sim.race.replay import replay_ticks

    track = resolve_track(TRACK)
    rules = replace(preset_rules(preset), window_seconds=40.0)
    live = list(race_ticks(track, rules, seed=2))
    result = live[-1].result
    assert result is not None
    replayed = replay_ticks(result, track)
    assert len(replayed) == len(live)
    worst = max(
        math.hypot(a[0] - b[0], a[1] - b[1])
        for tick, again in zip(live, replayed, strict=True)
        for a, b in zip(tick.objects, again.objects, strict=True)
    )
    assert worst < 0.01
    assert replay_ticks(result)[5].objects == ()  # without the track: the car alone


def test_the_camera_sees_each_cars_own_objects() -> None:
    from sim.physics.objects.settings import Lane, ObstacleSettings
    from sim.sensors import camera_scene as scene
    from sim.sensors.observations import Observer

    track = resolve_track(TRACK)
    boxes = RaceSettings(
        RaceType.OBJECT_AVOIDANCE, obstacles=ObstacleSettings(positions=((0.1, Lane.INNER),))
    )
    sim = TrackSimulation(track, 1, race=boxes)
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    x, y, yaw = float(field.x[0, 0]), float(field.y[0, 0]), float(field.heading[0, 0])
    sim.put(0, x - 1.0 * math.cos(yaw), y - 1.0 * math.sin(yaw), yaw)
    frame = Observer(sim, ("camera",)).observe()[0, ..., 0]
    plain = TrackSimulation(track, 1)
    plain.reset_car(0, start_s=0.0)
    plain.put(0, x - 1.0 * math.cos(yaw), y - 1.0 * math.sin(yaw), yaw)
    empty = Observer(plain, ("camera",)).observe()[0, ..., 0]
    # A box a metre ahead fills a block of its own grey in the middle of the picture.
    changed = frame != empty
    assert changed.sum() > 200
    assert (frame[changed] == scene.BOX_SIDE).mean() > 0.9
    middle = frame[:, 60:100]
    assert (middle == scene.BOX_SIDE).sum() > 100

    # Bot cars are drawn darker, moving with their clock.
    sim = TrackSimulation(track, 1, race=bots(count=1, speed=0.0))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    x, y, yaw = float(field.x[0, 0]), float(field.y[0, 0]), float(field.heading[0, 0])
    sim.put(0, x - 0.8 * math.cos(yaw), y - 0.8 * math.sin(yaw), yaw)
    frame = Observer(sim, ("camera",)).observe()[0, ..., 0]
    assert (frame == scene.BOT_CAR_SIDE).sum() > 100


def test_each_laps_crashes_are_counted_live_and_in_the_replay() -> None:
    from sim.race.replay import replay_ticks

    track = resolve_track(TRACK)
    live = list(race_ticks(track, preset_rules("head-to-bot"), seed=0))
    result = live[-1].result
    assert result is not None
    replayed = replay_ticks(result, track)
    assert max(tick.lap_crashes for tick in live) >= 1
    assert [t.lap_crashes for t in replayed] == [t.lap_crashes for t in live]
    # A lap's count starts again at the line.
    ends = [i for i in range(1, len(live)) if len(live[i].laps) > len(live[i - 1].laps)]
    assert all(live[i].lap_crashes == 0 for i in ends)


def test_an_evaluation_reset_lets_the_bots_drive_on_while_the_car_is_held() -> None:
    from sim.physics.resets import ResetRules
    from sim.training.trial_resets import TrialResets

    track = resolve_track(TRACK)
    sim = TrackSimulation(track, 1, race=bots(count=2, speed=0.5))
    sim.reset_car(0, start_s=0.0)
    field = sim.objects
    assert field is not None
    resets = TrialResets(track, 1, ResetRules(number_of_resets=3, collision_penalty=5.0))
    resets.before_step(sim)
    before = field.distance[0].copy()
    assert resets.put_back(sim, 0, EpisodeStatus.CRASHED)
    # Held 5 s for the crash, as simapp holds the car: the bots went 2.5 m on meanwhile.
    moved = (field.distance[0] - before) % track.length
    assert moved == pytest.approx([2.5, 2.5], abs=0.01)
    assert resets.penalty[0] == 5.0

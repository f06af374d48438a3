"""A model's race type reaches its training: an object-avoidance model's cars meet boxes,
its reward function sees them, and a head-to-bot model is refused in one sentence."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from sim.deepracer.files import write_training_params
from sim.env import BatchedDeepRacer
from sim.garage.folder import ModelError, ModelFolder
from sim.garage.options import new_model
from sim.training.config import model_env_config


def with_race(folder: ModelFolder, race_type: str, **keys: object) -> None:
    params = folder.training_params()
    changed = replace(params, race_type=race_type, extra={**params.extra, **keys})
    write_training_params(folder.training_params_file, changed)


def test_an_object_avoidance_model_trains_among_its_boxes() -> None:
    folder = new_model("dodger", sensors=["lidar"], reward="object_avoidance")
    with_race(folder, "OBJECT_AVOIDANCE", NUMBER_OF_OBSTACLES=3, RANDOMIZE_OBSTACLE_LOCATIONS=True)
    config = model_env_config(folder)
    assert config.race is not None and config.race.obstacles.boxes == 3
    env = BatchedDeepRacer(config, 4)
    env.reset()
    sim = env.sim
    assert sim.objects is not None
    params = sim.all_params()
    assert all(len(p["objects_location"]) == 3 for p in params)
    # The object_avoidance template pays for keeping away from them: it reads real boxes.
    rewards = [config.reward_functions(1)[0](p) for p in params]
    assert all(np.isfinite(rewards))


def test_a_time_trial_model_trains_without_boxes() -> None:
    folder = new_model("plain")
    assert model_env_config(folder).race is None


def test_a_head_to_bot_model_trains_among_its_bots_and_a_blind_one_is_refused() -> None:
    folder = new_model("chaser", sensors=["lidar"])
    with_race(folder, "HEAD_TO_BOT", NUMBER_OF_BOT_CARS=2, BOT_CAR_SPEED=0.5)
    config = model_env_config(folder)
    assert config.race is not None and config.race.bots.count == 2
    env = BatchedDeepRacer(config, 2)
    env.reset()
    before = env.sim.all_params()[0]["objects_distance"]
    for _ in range(15):
        env.sim.apply(np.zeros(2), np.zeros(2))
    params = env.sim.all_params()[0]
    # A second later each bot is half a metre further on, and says its speed.
    moved = [
        (b - a) % env.sim.track.length
        for a, b in zip(before, params["objects_distance"], strict=True)
    ]
    assert moved == pytest.approx([0.5, 0.5], abs=0.01)
    assert params["objects_speed"] == [0.5, 0.5]
    blind = new_model("blind", sensors=["vector"])
    with_race(blind, "HEAD_TO_BOT", NUMBER_OF_BOT_CARS=2)
    with pytest.raises(ModelError, match="needs a camera or a lidar"):
        model_env_config(blind)
    with_race(folder, "OBJECT_AVOIDANCE", NUMBER_OF_OBSTACLES=99)
    with pytest.raises(ModelError, match="NUMBER_OF_OBSTACLES must be a whole number from 0"):
        model_env_config(folder)


def test_training_keeps_where_the_bots_stood_at_its_last_traced_row() -> None:
    """The sim-trace has no object columns: the logbook keeps the objects of its last row
    beside it (sim.physics.objects.seen), for the app's agent's-eye view."""
    from sim.deepracer.files import last_sim_trace_row
    from sim.physics.objects.seen import read_seen
    from sim.training.logbook import Logbook

    folder = new_model("chaser", sensors=["lidar"])
    with_race(folder, "HEAD_TO_BOT", NUMBER_OF_BOT_CARS=3, BOT_CAR_SPEED=0.5)
    env = BatchedDeepRacer(model_env_config(folder), 2)
    logbook = Logbook(
        folder.path,
        cars=2,
        episodes_per_iteration=4,
        track_length=env.sim.track.length,
        waypoints=env.sim.track.center,
        discrete=True,
    )
    env.watcher = logbook
    env.reset()
    while logbook.episodes < 3:
        env.step(np.zeros(2, dtype=np.int64))  # hard right: off the road within seconds
    logbook.flush()
    seen = read_seen(folder.path)
    assert seen is not None and seen.bots and len(seen.poses) == 3
    traces = sorted(folder.training_trace_dir.glob("*-iteration.csv"))
    row = last_sim_trace_row(traces[-1])
    assert row is not None and (seen.episode, seen.steps) == (row.episode, row.steps)
    # Each bot stands in a lane, within the road: half a lane from the centre line.
    field = seen.field(env.sim.track)
    _, _, feet = field.lanes.centre.project(np.array(seen.poses)[:, :2])
    offsets = np.hypot(*(np.array(seen.poses)[:, :2] - feet).T)
    assert np.all(offsets < env.sim.track.width / 2)

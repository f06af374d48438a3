"""The gymnasium environment: API checks, DeepRacer episode rules, determinism."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

from sim.deepracer.action_space import discrete_grid
from sim.env import ENV_ID, BatchedDeepRacer, DeepRacerEnv, EnvConfig
from sim.sensors.observations import SensorOptions
from tests.sim.shapes import ring_track

SMALL_CAMERA = SensorOptions(camera_width=40, camera_height=30)


def make_env(sensors: tuple[str, ...] = ("vector",), **kwargs: Any) -> DeepRacerEnv:
    config = EnvConfig.build(ring_track(), sensors=sensors, sensor_options=SMALL_CAMERA, **kwargs)
    return DeepRacerEnv(config)


@pytest.mark.parametrize(
    "sensors",
    [("vector",), ("lidar",), ("camera",), ("SECTOR_LIDAR",), ("FRONT_FACING_CAMERA", "LIDAR")],
)
def test_passes_gymnasium_env_checker(sensors: tuple[str, ...]) -> None:
    gym_check_env(make_env(sensors), skip_render_check=True)


@pytest.mark.parametrize("sensors", [("vector",), ("camera",), ("camera", "lidar")])
def test_passes_stable_baselines3_env_checker(sensors: tuple[str, ...]) -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    sb3_check_env(make_env(sensors), warn=False)


def test_discrete_action_space_env_passes_checks() -> None:
    env = make_env(action_space=discrete_grid(30.0, 5, 2.0, 2).to_metadata())
    assert isinstance(env.action_space, gym.spaces.Discrete)
    assert env.action_space.n == 10
    gym_check_env(env, skip_render_check=True)


def test_registered_with_gymnasium() -> None:
    env = gym.make(ENV_ID, track=ring_track())
    obs, info = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    assert info["status"] == "In progress"


def test_first_step_is_a_prepare_step_with_zero_reward() -> None:
    calls: list[int] = []

    def reward(params: Mapping[str, Any]) -> float:
        calls.append(int(params["steps"]))
        return 1.0

    env = make_env(reward=reward)
    env.reset(options={"start": 0.0})
    _, first, *_ = env.step(np.array([0.0, -0.5], dtype=np.float32))
    _, second, *_ = env.step(np.array([0.0, -0.5], dtype=np.float32))
    assert first == 0.0
    assert second == 1.0
    assert calls == [2]


def test_same_seed_and_actions_give_the_same_episode() -> None:
    def rollout() -> list[float]:
        env = make_env(("vector", "lidar"))
        env.reset(seed=42)
        rng = np.random.default_rng(3)
        trace = []
        for _ in range(60):
            obs, reward, terminated, truncated, info = env.step(
                rng.uniform(-1, 1, 2).astype(np.float32)
            )
            trace += [reward, info["x"], info["y"], float(obs["lidar"].sum())]
            if terminated or truncated:
                env.reset()
        return trace

    assert rollout() == rollout()


def test_starts_move_round_the_track_between_episodes() -> None:
    env = make_env()
    starts = []
    for _ in range(3):
        env.reset()
        starts.append(env.params()["projection_distance"])
    length = env.config.track.length
    gaps = np.mod(np.diff(starts), length)
    assert np.allclose(gaps, 0.05 * length, atol=0.02)


def test_leaving_the_track_terminates_with_status_off_track() -> None:
    env = make_env()
    env.reset(options={"start": 0.0})
    for _ in range(200):
        _, _, terminated, truncated, info = env.step(np.array([-1.0, 1.0], dtype=np.float32))
        if terminated or truncated:
            break
    assert terminated
    assert info["status"] == "Off track"


def test_batched_env_resets_finished_cars_and_keeps_final_observation() -> None:
    config = EnvConfig.build(ring_track(), sensors=("vector",))
    env = BatchedDeepRacer(config, 4)
    env.reset()
    actions = np.tile(np.array([[-1.0, 1.0]], dtype=np.float32), (4, 1))  # hard right at speed
    finished = np.zeros(4, dtype=bool)
    for _ in range(100):
        obs, _, terminated, _, infos = env.step(actions)
        for car in np.flatnonzero(terminated):
            assert infos[car].status == "Off track"
            assert env.sim.steps[car] == 0  # already reset for its next episode
            assert env.sim.status[car] == "In progress"
        finished |= terminated
        if finished.all():
            break
    assert finished.all()
    assert all(final is not None for final in env.final_observations)
    assert obs.shape == (4, env.observation_space.shape[0])


@pytest.mark.parametrize("sensors", [("vector",), ("lidar",), ("FRONT_FACING_CAMERA", "LIDAR")])
def test_restarted_cars_observe_what_a_fresh_observation_shows(sensors: tuple[str, ...]) -> None:
    # Only the cars that restarted are observed again after a reset: their rows must be
    # exactly what observing the whole fleet from scratch gives.
    config = EnvConfig.build(ring_track(), sensors=sensors, sensor_options=SMALL_CAMERA)
    env = BatchedDeepRacer(config, 6)
    env.reset()
    actions = np.tile(np.array([[0.0, 1.0]], dtype=np.float32), (6, 1))
    actions[0] = [-1.0, 1.0]  # one car turns hard off the road and restarts alone
    restarted_any = False
    for _ in range(60):
        obs, _, terminated, truncated, _ = env.step(actions)
        restarted_any |= bool((terminated | truncated).any())
        fresh = env.observer.observe()
        for key in fresh if isinstance(fresh, dict) else [None]:
            got, want = (obs[key], fresh[key]) if key else (obs, fresh)
            assert np.array_equal(got, want)
    assert restarted_any


def test_reward_errors_reach_the_caller() -> None:
    from sim.reward.errors import RewardFunctionError
    from sim.reward.function import load_reward_source

    bad = load_reward_source("def reward_function(params):\n    return params['nope']\n", "bad.py")
    env = make_env(reward=bad)
    env.reset()
    env.step(np.zeros(2, dtype=np.float32))  # prepare step: function not called
    with pytest.raises(RewardFunctionError, match=r"bad\.py.*line 2"):
        env.step(np.zeros(2, dtype=np.float32))

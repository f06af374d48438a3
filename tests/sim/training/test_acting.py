"""A training's acting: the policy's draws, values and log-probabilities for each car, and
the values PPO bootstraps from where the step limit cuts an episode."""

from __future__ import annotations

import multiprocessing
import pickle
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
import torch
from stable_baselines3.common.distributions import make_proba_distribution

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata, default_hyperparameters
from sim.env import EnvConfig
from sim.physics.simulation import EpisodeRules
from sim.training.acting import Acting
from sim.training.actor import PolicyActor, pooled_observations, training_mode
from sim.training.policy import PolicyNetwork, init_weights, network_spec, observation_tensors
from sim.training.ppo import PPOSettings, make_ppo
from sim.training.ppo_loss import evaluate_actions
from sim.training.shared_frames import SharedFrames
from sim.training.vec_env import BatchedVecEnv

CARS = 3
STEP_LIMIT = 4


def _fleet(sensor: str, rules: EpisodeRules | None = None) -> tuple[BatchedVecEnv, PolicyActor]:
    metadata = ModelMetadata(discrete_grid(30.0, 3, 2.0, 1), (sensor,))
    config = EnvConfig.build("hairpin-circuit", metadata.action_space, (sensor,))
    if rules is not None:
        config = replace(config, rules=rules)
    env = BatchedVecEnv(config, CARS, seed=3)
    network = PolicyNetwork(network_spec(metadata))
    init_weights(network)
    return env, PolicyActor(network, make_proba_distribution(env.action_space), bf16=False)


def _values(actor: PolicyActor, obs: Any) -> np.ndarray:
    network = actor.network
    with torch.no_grad(), training_mode(network, bf16=False):
        pooled = observation_tensors(pooled_observations(network, obs))
        return network.value(network.features(pooled)).flatten().numpy()


@pytest.mark.parametrize("sensor", ["vector", "camera"])
def test_acting_keeps_each_cars_value_and_the_log_probability_of_its_draw(sensor: str) -> None:
    env, actor = _fleet(sensor)
    obs = env.reset()
    acting = actor.act(obs)
    assert acting.actions.shape == (CARS,) and acting.values.dtype == np.float32
    assert np.array_equal(acting.values, _values(actor, obs))
    network = actor.network
    with torch.no_grad(), training_mode(network, bf16=False):
        _, log_probs, _ = evaluate_actions(
            network,
            make_proba_distribution(env.action_space),
            observation_tensors(acting.pooled),
            torch.as_tensor(acting.actions),
        )
    assert np.allclose(acting.log_probs, log_probs.numpy(), atol=1e-6)


def test_the_step_limit_cutting_episodes_leaves_the_values_of_their_last_observations() -> None:
    env, actor = _fleet("vector", EpisodeRules(max_steps=STEP_LIMIT))
    env.reset()
    acting = env.act(actor)
    cut: dict[int, float] = {}
    for _ in range(STEP_LIMIT):
        assert not cut  # no episode is cut before the limit
        _, dones, acting = env.step_and_act(acting, actor)
        cut = acting.final_values
    # Every car still on the road reached the limit; its last observation's value is kept.
    assert cut and set(cut) <= set(np.flatnonzero(dones).tolist())
    finals = env.batch.final_observations
    for car, value in cut.items():
        assert value == pytest.approx(float(_values(actor, finals[car][None, ...])[0]), abs=1e-6)


def test_a_rollout_bootstraps_a_cut_episode_from_the_value_where_it_was_cut() -> None:
    hyperparameters = default_hyperparameters()
    settings = PPOSettings.from_hyperparameters(hyperparameters)
    env, _ = _fleet("vector", EpisodeRules(max_steps=STEP_LIMIT))
    metadata = ModelMetadata(discrete_grid(30.0, 3, 2.0, 1), ("vector",))
    model = make_ppo(env, network_spec(metadata), settings, max_samples=CARS * STEP_LIMIT, seed=2)
    raw: list[np.ndarray] = []
    following: list[Acting] = []
    step_and_act = env.step_and_act

    def watched(acting: Acting, actor: PolicyActor) -> tuple[Any, Any, Acting]:
        rewards, dones, nxt = step_and_act(acting, actor)
        raw.append(rewards.copy())
        following.append(nxt)
        return rewards, dones, nxt

    env.step_and_act = watched  # type: ignore[method-assign]
    model.start_rollouts()
    model.collect(episodes_wanted=10_000, min_samples=1, max_samples=CARS * STEP_LIMIT)
    last = following[STEP_LIMIT - 1].final_values
    assert last, "the step limit cut no episode"
    stored = model.rollout_buffer.rewards[STEP_LIMIT - 1]
    for car in range(CARS):
        bootstrap = model.gamma * last[car] if car in last else 0.0
        assert stored[car] == pytest.approx(raw[STEP_LIMIT - 1][car] + bootstrap, abs=1e-5)


@pytest.mark.parametrize("sensors", [("camera",), ("camera", "lidar")])
def test_a_parts_frames_cross_in_shared_memory_and_come_back_the_same(
    sensors: tuple[str, ...],
) -> None:
    rng = np.random.default_rng(5)
    frames = rng.random((CARS, 60, 80, 1), dtype=np.float32)
    pooled: Any = frames
    if "lidar" in sensors:
        pooled = {"camera": frames, "lidar": rng.random((CARS, 64), dtype=np.float32)}
    acting = Acting(pooled, np.arange(CARS), np.zeros(CARS, np.float32), np.zeros(CARS))
    shared = SharedFrames.allocate(multiprocessing.get_context("spawn"), CARS, (60, 80, 1))
    sent = shared.put(acting)
    left = sent.pooled["camera"] if isinstance(sent.pooled, dict) else sent.pooled
    assert left is None  # the frames do not go through the pipe
    back = shared.take(pickle.loads(pickle.dumps(sent)))
    # The part's next answer writes the memory again: the trainer's frames are its own copy.
    shared.put(Acting(np.zeros_like(frames), acting.actions, acting.values, acting.log_probs))
    got = back.pooled["camera"] if isinstance(back.pooled, dict) else back.pooled
    assert np.array_equal(got, frames)
    if isinstance(pooled, dict):
        assert np.array_equal(back.pooled["lidar"], pooled["lidar"])

"""A training's acting: the policy samples each car's action on each step, as PPO needs it.

The trainer acts with the network it is training. A simulation process of a camera model's
training acts for its own cars with a copy (sim.training.shards): the trainer sends the
weights at the start of every rollout, so every action of a rollout still comes from the
weights being trained and PPO stays DeepRacer's synchronous one, while the forward passes,
about half of a camera training's collection, run on every core instead of the trainer's.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3.common.distributions import Distribution, make_proba_distribution

from sim.training.acting import Acting, joined_observations
from sim.training.policy import (
    NetworkSpec,
    Observation,
    PolicyNetwork,
    fill_network,
    observation_tensors,
    open_tensors,
    policy_bytes,
    pooled_frames,
)
from sim.training.ppo_loss import action_distribution


def sampled(
    network: PolicyNetwork, template: Distribution, obs: Observation, deterministic: bool = False
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Actions drawn from the policy for `obs` (its mode where `deterministic`), the values
    of `obs`, and the actions' log-probabilities."""
    features = network.features(obs)
    distribution = action_distribution(network, template, network.action_parameters(features))
    actions = distribution.get_actions(deterministic=deterministic)
    return actions, network.value(features), distribution.log_prob(actions)


def pooled_observations(network: PolicyNetwork, obs: Any) -> Any:
    """Observations with their camera frames as `pooled_frames` makes them: what a
    training's forward passes read and its rollout buffer keeps."""
    if network.camera is None:
        return obs
    if isinstance(obs, dict):
        return {**obs, "camera": pooled_frames(obs["camera"])}
    return pooled_frames(obs)


@contextmanager
def training_mode(network: PolicyNetwork, bf16: bool) -> Iterator[None]:
    """The network as a training runs it, acting and updating alike: camera frames as
    `pooled_observations` gives them, and the convolutions in bfloat16 where `bf16`.
    Evaluations and races run it as it is: float32, the Observer's frames."""
    network.frames_prepared = True
    network.bf16_convolutions = bf16 and network.camera is not None
    try:
        yield
    finally:
        network.frames_prepared = False
        network.bf16_convolutions = False


@dataclass(frozen=True)
class ActorSetup:
    """What a simulation process needs to act for its cars (plain data: it is pickled)."""

    spec: NetworkSpec
    bf16: bool  # the training's convolutions in bfloat16 (`make_ppo` decides)


class PolicyActor:
    """Samples actions for cars' observations with `network`, as a training acts."""

    def __init__(self, network: PolicyNetwork, template: Distribution, bf16: bool) -> None:
        self.network = network
        self._template = template
        self._bf16 = bf16

    @classmethod
    def copy_for(
        cls,
        setup: ActorSetup,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        cars: int,
        seed: int | None,
    ) -> PolicyActor:
        """An actor with a network of its own for `cars` cars of these spaces (a car's), in
        a simulation process: one thread (the process is one core's worth of the
        fleet), its draws seeded by `seed` (None: by the system), weights from `load`.
        It acts once on blank observations before it returns, so whatever torch loads for
        its first forward pass is loaded before the process's files are closed off."""
        torch.set_num_threads(1)
        if seed is not None:
            torch.manual_seed(seed)
        network = PolicyNetwork(setup.spec)
        network.eval()
        actor = cls(network, make_proba_distribution(action_space), setup.bf16)
        actor.act(_blank(observation_space, cars))
        return actor

    def weights(self) -> bytes:
        """The network's weights, for a copy's `load`."""
        return policy_bytes(self.network)

    def load(self, weights: bytes) -> None:
        """Act from now on with `weights` (from the trainer's actor's `weights`)."""
        facts, tensors = open_tensors(weights, "the training's policy")
        fill_network(self.network, facts, tensors, "the training's policy")

    def act(self, obs: Any, finals: Mapping[int, Any] | None = None) -> Acting:
        """The policy's actions for `obs` (one row a car), with the values of `finals`: the
        final observations of the cars whose episodes the step limit has just cut."""
        network = self.network
        pooled = pooled_observations(network, obs)
        with torch.no_grad(), training_mode(network, self._bf16):
            actions, values, log_probs = sampled(
                network, self._template, observation_tensors(pooled)
            )
            final_values: dict[int, float] = {}
            if finals:
                cars = sorted(finals)
                stacked = joined_observations([_batch_of_one(finals[car]) for car in cars])
                last = network.value(
                    network.features(observation_tensors(pooled_observations(network, stacked)))
                )
                final_values = dict(zip(cars, last.flatten().tolist(), strict=True))
        return Acting(
            pooled=pooled,
            actions=actions.numpy(),
            values=values.flatten().numpy(),
            log_probs=log_probs.numpy(),
            final_values=final_values,
        )


def _batch_of_one(obs: Any) -> Any:
    if isinstance(obs, dict):
        return {key: value[None, ...] for key, value in obs.items()}
    return obs[None, ...]


def _blank(space: spaces.Space[Any], cars: int) -> Any:
    """Zeros as `cars` observations of `space`."""
    if isinstance(space, spaces.Dict):
        return {key: _blank(sub, cars) for key, sub in space.spaces.items()}
    assert space.shape is not None and space.dtype is not None
    return np.zeros((cars, *space.shape), dtype=space.dtype)

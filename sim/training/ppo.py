"""DeepRacer's clipped PPO on SB3, with the value loss DeepRacer uses.

SB3's PPO trains the value function with a mean squared error; DeepRacer's `loss_type`
hyperparameter chooses between "huber" (its console default) and "mean squared error".
`RacerPPO` keeps SB3's machinery (rollout buffer, GAE, distributions, Adam) and replaces
two pieces:

- `train`: the clipped PPO update, with `value_loss` picking F.smooth_l1_loss (Huber,
  delta 1) or F.mse_loss from `loss_type`;
- `collect`: rollouts gathered until `num_episodes_between_training` episodes have
  finished across all the cars (DeepRacer's rollout size), within a floor and a cap on the
  number of samples, while noting the episodes a racer watches (sim-trace rows are the
  trainer's logbook's, which sees every car).

DeepRacer hyperparameters map one to one: batch_size -> minibatch size, num_epochs ->
n_epochs, lr -> learning rate, beta_entropy -> ent_coef, discount_factor -> gamma; clip
0.2, GAE lambda 0.95 and Adam epsilon 1e-5 are DeepRacer's fixed internals.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.buffers import DictRolloutBuffer, RolloutBuffer
from stable_baselines3.common.distributions import Distribution
from stable_baselines3.common.policies import ActorCriticPolicy

from sim.deepracer.files import ADAM_EPSILON, GAE_LAMBDA, PPO_CLIP, SIMAPP_LOSS_TYPE
from sim.garage.folder import BF16_CONVOLUTIONS, FLOAT32
from sim.training.actor import PolicyActor, sampled, training_mode
from sim.training.logbook import FinishedEpisode
from sim.training.minibatch_shares import MinibatchShares
from sim.training.policy import (
    NetworkSpec,
    PolicyNetwork,
    init_weights,
    native_bf16,
    pooled_frame_shape,
)
from sim.training.ppo_loss import (
    FIGURES,
    LossSettings,
    Minibatch,
    action_distribution,
    evaluate_actions,
    normalized_advantages,
    slice_samples,
    value_loss,
)
from sim.training.vec_env import FleetVecEnv

LOSS_TYPES = ("huber", "mean squared error")


@dataclass(frozen=True)
class PPOSettings:
    """SB3 PPO arguments from DeepRacer hyperparameters (see the module docstring)."""

    learning_rate: float
    batch_size: int
    n_epochs: int
    gamma: float
    ent_coef: float
    loss_type: str
    episodes_per_update: int
    clip_range: float = PPO_CLIP
    gae_lambda: float = GAE_LAMBDA
    adam_epsilon: float = ADAM_EPSILON
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5

    @classmethod
    def from_hyperparameters(cls, values: Mapping[str, float | int | str]) -> PPOSettings:
        loss_type = str(values.get("loss_type", SIMAPP_LOSS_TYPE))
        if loss_type not in LOSS_TYPES:
            raise ValueError(
                f"loss_type must be 'huber' or 'mean squared error', not {loss_type!r}."
            )
        return cls(
            learning_rate=float(values.get("lr", 3e-4)),
            batch_size=int(values.get("batch_size", 64)),
            n_epochs=int(values.get("num_epochs", 10)),
            gamma=float(values.get("discount_factor", 0.999)),
            ent_coef=float(values.get("beta_entropy", 0.01)),
            loss_type=loss_type,
            episodes_per_update=int(values.get("num_episodes_between_training", 20)),
        )


class RacerPolicy(ActorCriticPolicy):
    """SB3's actor-critic interface over our `PolicyNetwork` (which races use unchanged)."""

    net: PolicyNetwork

    def __init__(self, *args: Any, spec: NetworkSpec, **kwargs: Any) -> None:
        self.spec = spec
        kwargs["ortho_init"] = False  # `build_network`'s own initialisation is used
        super().__init__(*args, **kwargs)

    def _build(self, lr_schedule: Any) -> None:
        self.net = PolicyNetwork(self.spec)
        init_weights(self.net)
        self.optimizer = torch.optim.Adam(
            self.net.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data: dict[str, Any] = super()._get_constructor_parameters()
        data["spec"] = self.spec
        return data

    def _distribution(self, params: torch.Tensor) -> Distribution:
        return action_distribution(self.net, self.action_dist, params)

    def forward(
        self, obs: Any, deterministic: bool = False
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        actions, values, log_prob = sampled(self.net, self.action_dist, obs, deterministic)
        return actions.reshape((-1, *(self.action_space.shape or ()))), values, log_prob

    def evaluate_actions(
        self, obs: Any, actions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        return evaluate_actions(self.net, self.action_dist, obs, actions)

    def get_distribution(self, obs: Any) -> Distribution:
        return self._distribution(self.net.action_parameters(self.net.features(obs)))

    def predict_values(self, obs: Any) -> torch.Tensor:
        return self.net.value(self.net.features(obs))


@dataclass(frozen=True)
class UpdateStats:
    """Means over one `train` call's minibatches."""

    entropy: float
    policy_loss: float
    value_loss: float
    approx_kl: float
    clip_fraction: float


@dataclass
class Rollout:
    """What one `collect` gathered besides the samples."""

    steps: int  # env steps, all cars
    episodes: list[FinishedEpisode]


class RacerPPO(PPO):
    """PPO whose value loss follows DeepRacer's `loss_type` and whose rollouts are sized in
    episodes. Build it with `make_ppo`."""

    loss_type: str = "huber"
    # Threads of the update: the simulation processes wait while it runs, so their cores
    # are free; a camera network's update is most of a training's time (sim.training.shards).
    update_threads: int = 1
    # A training's convolutions, acting and updating, in bfloat16 (`make_ppo` decides;
    # PolicyNetwork says how).
    bf16_training: bool = False

    @staticmethod
    def _wrap_env(env: Any, verbose: int = 0, monitor_wrapper: bool = True) -> Any:
        # Our VecEnv is used as it is: no Monitor, no channel-first transpose for images
        # (the network reads the Observer's channel-last frames directly).
        return env

    @property
    def batched_env(self) -> FleetVecEnv:
        assert isinstance(self.env, FleetVecEnv)
        return self.env

    @property
    def network(self) -> PolicyNetwork:
        """The policy network being trained (what `policy.safetensors` holds)."""
        assert isinstance(self.policy, RacerPolicy)
        return self.policy.net

    def value_loss(self, values: torch.Tensor, returns: torch.Tensor) -> torch.Tensor:
        """DeepRacer's value loss: Huber (smooth L1, delta 1) or mean squared error."""
        return value_loss(values, returns, self.loss_type)

    # --- learning ------------------------------------------------------------------------
    def train(self) -> None:
        """The clipped PPO update over the rollout buffer; stats in `last_update`."""
        shares = self._shares()
        # A camera network's update takes `update_threads` threads of its own, each with one
        # core's kernels (sim.training.minibatch_shares); a small network's, torch's threads.
        torch.set_num_threads(1 if shares.threads > 1 else self.update_threads)
        try:
            with shares.running():
                self._update(shares)
        finally:
            # Collection runs one small forward pass a step: one thread, the cores are the
            # simulation's.
            torch.set_num_threads(1)

    def _shares(self) -> MinibatchShares:
        threads = self.update_threads if self.network.camera is not None else 1
        return MinibatchShares(self.network, self.policy.action_dist, threads)

    def _update(self, shares: MinibatchShares) -> None:
        self.policy.set_training_mode(True)
        for group in self.policy.optimizer.param_groups:  # DeepRacer's lr is constant
            group["lr"] = float(self.lr_schedule(self._current_progress_remaining))
        schedule = self.clip_range
        clip = float(schedule(self._current_progress_remaining) if callable(schedule) else schedule)
        settings = LossSettings(
            clip=clip,
            ent_coef=float(self.ent_coef),
            vf_coef=float(self.vf_coef),
            loss_type=self.loss_type,
            normalize_advantage=bool(self.normalize_advantage),
            discrete=isinstance(self.action_space, spaces.Discrete),
        )
        with training_mode(self.network, self.bf16_training):
            totals, batches = self._epochs(settings, shares)
        self._n_updates += self.n_epochs
        means = totals / max(batches, 1)
        self.last_update = UpdateStats(*(float(value) for value in means))

    def _epochs(self, settings: LossSettings, shares: MinibatchShares) -> tuple[np.ndarray, int]:
        """DeepRacer's epochs over the rollout in this process: the `FIGURES` summed over
        minibatches, and how many there were."""
        totals = np.zeros(len(FIGURES))
        batches = 0
        pieces = slice_samples(self.network)
        for _ in range(self.n_epochs):
            for batch in self.rollout_buffer.get(self.batch_size):
                samples = Minibatch.of(
                    batch.observations,
                    actions=batch.actions,
                    old_log_prob=batch.old_log_prob,
                    advantages=normalized_advantages(
                        batch.advantages, settings.normalize_advantage
                    ),
                    returns=batch.returns,
                    discrete=settings.discrete,
                )
                totals += shares.gradients(samples, settings, pieces)
                self._step()
                batches += 1
        return totals, batches

    def _step(self) -> None:
        """One optimizer step on the minibatch's gradients, clipped as DeepRacer clips."""
        torch.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm, foreach=True)
        self.policy.optimizer.step()

    # --- gathering experience ----------------------------------------------------------------
    def start_rollouts(self) -> None:
        """Reset every car; call once before the first `collect`."""
        self.batched_env.reset()
        self._actor = PolicyActor(self.network, self.policy.action_dist, self.bf16_training)
        self._starts = np.ones(self.n_envs, dtype=bool)
        self._episode_rewards = np.zeros(self.n_envs)
        self._episodes_by_car = np.zeros(self.n_envs, dtype=np.int64)

    def collect(self, episodes_wanted: int, min_samples: int, max_samples: int) -> Rollout:
        """Fill the rollout buffer until `episodes_wanted` episodes have finished across the
        cars and at least `min_samples` samples are in, or `max_samples` are reached."""
        env = self.batched_env
        buffer = self.rollout_buffer
        n = self.n_envs
        max_steps = max(1, max_samples // n)
        min_steps = min(max_steps, max(1, math.ceil(min_samples / n)))
        _resize(buffer, max_steps)
        buffer.reset()
        self.policy.set_training_mode(False)
        discrete = env.config.action_space.kind == "discrete"
        finished: list[FinishedEpisode] = []
        dones = np.zeros(n, dtype=bool)
        # The weights have changed since the last rollout: every car acts again on the
        # observation it stands at (the fleet's simulation processes get the new weights).
        acting = env.act(self._actor)
        steps = 0
        while steps < max_steps:
            rewards, dones, following = env.step_and_act(acting, self._actor)
            details = env.last_infos
            self._episode_rewards += rewards
            for car, value in following.final_values.items():
                # Cut by the step limit, not ended: bootstrap from the value there.
                rewards[car] += self.gamma * value
            for car in np.flatnonzero(dones).tolist():
                info = details[car]
                finished.append(
                    FinishedEpisode(
                        car=car,
                        reward=float(self._episode_rewards[car]),
                        progress=info.progress,
                        status=str(info.status),
                        steps=info.steps,
                    )
                )
                self._episode_rewards[car] = 0.0
                self._episodes_by_car[car] += 1
            buffer.add(
                acting.pooled,
                acting.actions.reshape(n, -1) if not discrete else acting.actions.reshape(n, 1),
                rewards,
                self._starts,
                torch.as_tensor(acting.values),
                torch.as_tensor(acting.log_probs),
            )
            acting = following
            self._starts = dones
            steps += 1
            if len(finished) >= episodes_wanted and steps >= min_steps:
                break
        _truncate(buffer, steps)
        # The last observations' values, from the weights the rollout was collected with.
        buffer.compute_returns_and_advantage(
            last_values=torch.as_tensor(acting.values), dones=dones
        )
        self.num_timesteps += steps * n
        return Rollout(steps=steps * n, episodes=finished)


def pooled_buffer(model: RacerPPO) -> RolloutBuffer:
    """A rollout buffer for the model that keeps camera frames pooled (`pooled_frames`): a
    quarter of the raw frames' memory, and nothing left to prepare for the update."""
    space = model.observation_space
    pooled: spaces.Space[Any]
    if isinstance(space, spaces.Dict):
        pooled = spaces.Dict({key: _pooled_space(key, sub) for key, sub in space.spaces.items()})
    else:
        pooled = _pooled_space("camera", space)
    buffer: RolloutBuffer = type(model.rollout_buffer)(
        model.n_steps,
        pooled,
        model.action_space,
        device=model.device,
        gamma=model.gamma,
        gae_lambda=model.gae_lambda,
        n_envs=model.n_envs,
    )
    return buffer


def _pooled_space(sensor: str, space: spaces.Space[Any]) -> spaces.Space[Any]:
    if sensor != "camera":
        return space
    assert space.shape is not None
    return spaces.Box(0.0, 1.0, pooled_frame_shape(space.shape), dtype=np.float32)


_BUFFER_ARRAYS = (
    "actions",
    "rewards",
    "returns",
    "episode_starts",
    "values",
    "log_probs",
    "advantages",
)


def _resize(buffer: RolloutBuffer, steps: int) -> None:
    """Give the buffer room for `steps` steps per car (takes effect at `reset`)."""
    buffer.buffer_size = steps


def _truncate(buffer: RolloutBuffer, steps: int) -> None:
    """Keep the first `steps` rows: a rollout may end early once enough episodes finished."""
    for name in _BUFFER_ARRAYS:
        setattr(buffer, name, getattr(buffer, name)[:steps])
    if isinstance(buffer, DictRolloutBuffer):
        buffer.observations = {key: value[:steps] for key, value in buffer.observations.items()}
    else:
        buffer.observations = buffer.observations[:steps]
    buffer.buffer_size = steps
    buffer.pos = steps
    buffer.full = True


def training_numerics(spec: NetworkSpec) -> str:
    """How a training on this machine computes the network `spec` describes: bfloat16
    convolutions for a camera where the CPU has bfloat16 in hardware, float32 otherwise.
    Recorded on the model, as the physics it learnt is (`ModelFolder.trained_numerics`)."""
    return BF16_CONVOLUTIONS if spec.conv and native_bf16() else FLOAT32


def make_ppo(
    env: FleetVecEnv,
    spec: NetworkSpec,
    settings: PPOSettings,
    *,
    max_samples: int,
    seed: int | None = None,
    update_threads: int = 1,
) -> RacerPPO:
    """A RacerPPO on `env` with the network `spec` and DeepRacer-mapped `settings`."""
    torch.set_num_threads(1)  # tiny networks: threads cost more than they give
    with warnings.catch_warnings():
        # SB3 warns about a minibatch remainder; rollouts here vary in size by design.
        warnings.simplefilter("ignore", UserWarning)
        model = RacerPPO(
            RacerPolicy,
            env,
            learning_rate=settings.learning_rate,
            n_steps=max(2, max_samples // env.num_envs),
            batch_size=settings.batch_size,
            n_epochs=settings.n_epochs,
            gamma=settings.gamma,
            gae_lambda=settings.gae_lambda,
            clip_range=settings.clip_range,
            ent_coef=settings.ent_coef,
            vf_coef=settings.vf_coef,
            max_grad_norm=settings.max_grad_norm,
            policy_kwargs={
                "spec": spec,
                # foreach: one kernel per step for all tensors, not one per tensor.
                "optimizer_kwargs": {"eps": settings.adam_epsilon, "foreach": True},
            },
            device="cpu",
            seed=seed,
            verbose=0,
        )
    model.loss_type = settings.loss_type
    model.update_threads = update_threads
    model.bf16_training = training_numerics(spec) == BF16_CONVOLUTIONS
    if spec.conv:
        model.rollout_buffer = pooled_buffer(model)
    return model

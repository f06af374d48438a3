"""DeepRacer's clipped PPO loss, for a whole minibatch or any slice of one.

The update takes each minibatch of DeepRacer's `batch_size` in slices of at most
`slice_samples` samples, and adds up their gradients before the one optimizer step: a
camera network's working memory for 512 frames spills out of the CPU's caches, and slices
train faster a sample (docs/camera-learner-profile.md).

A slice's loss is its sums divided by the whole minibatch's size, and its advantages are
normalised over the whole minibatch, so the slices' gradients add up to the gradient of the
minibatch's mean loss: the same update however it is sliced, up to the order of float
additions. The five figures an update reports (`FIGURES`) add up the same way, and so do
the shares of a minibatch that threads compute side by side (sim.training.minibatch_shares).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.distributions import Distribution
from torch.nn import functional

from sim.training.policy import Observation, PolicyNetwork

FIGURES = ("entropy", "policy_loss", "value_loss", "approx_kl", "clip_fraction")

# Samples computed at a time, the best of 512, 256, 128 and 64 measured on a default camera
# model's whole update (4,096 samples, minibatches of 512) on 1 and 2 threads.
CAMERA_SLICE_SAMPLES = 128
CAMERA_SLICE_SAMPLES_BF16 = 256

# (values, log-probabilities, entropy) of the given actions under the current policy.
Evaluate = Callable[[Observation, torch.Tensor], tuple[torch.Tensor, torch.Tensor, Any]]


@dataclass(frozen=True)
class LossSettings:
    """What the loss needs besides the samples."""

    clip: float
    ent_coef: float
    vf_coef: float
    loss_type: str  # DeepRacer's: "huber" or "mean squared error"
    normalize_advantage: bool
    discrete: bool


def value_loss(
    values: torch.Tensor, returns: torch.Tensor, loss_type: str, reduction: str = "mean"
) -> torch.Tensor:
    """DeepRacer's value loss: Huber (smooth L1, delta 1) or mean squared error."""
    if loss_type == "huber":
        return functional.smooth_l1_loss(values, returns, reduction=reduction)
    return functional.mse_loss(values, returns, reduction=reduction)


def normalized_advantages(advantages: torch.Tensor, normalize: bool) -> torch.Tensor:
    """A whole minibatch's advantages, normalised as SB3's PPO does when asked to."""
    if normalize and len(advantages) > 1:
        return (advantages - advantages.mean()) / (advantages.std() + 1e-8)
    return advantages


def slice_samples(network: PolicyNetwork) -> int | None:
    """Samples to compute at a time; None: the whole minibatch at once."""
    if network.camera is None:
        return None
    return CAMERA_SLICE_SAMPLES_BF16 if network.bf16_convolutions else CAMERA_SLICE_SAMPLES


def action_distribution(
    network: PolicyNetwork, template: Distribution, params: torch.Tensor
) -> Distribution:
    """The policy's distribution over actions for the network's action parameters."""
    if network.spec.action_kind == "discrete":
        return template.proba_distribution(action_logits=params)
    return template.proba_distribution(params, network.log_std)


def evaluate_actions(
    network: PolicyNetwork, template: Distribution, obs: Observation, actions: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
    """Values, log-probabilities and entropy of `actions` under the current policy."""
    features = network.features(obs)
    distribution = action_distribution(network, template, network.action_parameters(features))
    return network.value(features), distribution.log_prob(actions), distribution.entropy()


@dataclass(frozen=True)
class Minibatch:
    """One minibatch's samples, advantages already normalised over all of them."""

    observations: Observation
    actions: torch.Tensor
    old_log_prob: torch.Tensor
    advantages: torch.Tensor
    returns: torch.Tensor

    @classmethod
    def of(
        cls,
        observations: Observation,
        *,
        actions: torch.Tensor,
        old_log_prob: torch.Tensor,
        advantages: torch.Tensor,
        returns: torch.Tensor,
        discrete: bool,
    ) -> Minibatch:
        """From the buffer's tensors (advantages as `normalized_advantages` gives them)."""
        actions = actions.long().flatten() if discrete else actions
        return cls(observations, actions, old_log_prob, advantages, returns)

    def __len__(self) -> int:
        return len(self.returns)

    def part(self, start: int, end: int) -> Minibatch:
        obs = self.observations
        sliced: Observation = (
            {key: value[start:end] for key, value in obs.items()}
            if isinstance(obs, dict)
            else obs[start:end]
        )
        return Minibatch(
            sliced,
            self.actions[start:end],
            self.old_log_prob[start:end],
            self.advantages[start:end],
            self.returns[start:end],
        )


def slice_loss(
    evaluate: Evaluate, samples: Minibatch, size: int, settings: LossSettings
) -> tuple[torch.Tensor, np.ndarray]:
    """`samples`' share of the loss of a minibatch of `size` samples, and its share of the
    five `FIGURES`."""
    values, log_prob, entropy = evaluate(samples.observations, samples.actions)
    values = values.flatten()
    log_ratio = log_prob - samples.old_log_prob
    ratio = torch.exp(log_ratio)
    clipped = torch.clamp(ratio, 1.0 - settings.clip, 1.0 + settings.clip)
    advantages = samples.advantages
    policy_loss = -torch.min(advantages * ratio, advantages * clipped).sum() / size
    value_part = value_loss(values, samples.returns, settings.loss_type, "sum") / size
    entropy_part = entropy.sum() / size
    loss = policy_loss - settings.ent_coef * entropy_part + settings.vf_coef * value_part
    with torch.no_grad():
        approx_kl = ((ratio - 1.0) - log_ratio).sum() / size
        clip_fraction = ((ratio - 1.0).abs() > settings.clip).float().sum() / size
    figures = np.array(
        [
            float(entropy_part.detach()),
            float(policy_loss.detach()),
            float(value_part.detach()),
            float(approx_kl),
            float(clip_fraction),
        ]
    )
    return loss, figures


def share_gradients(
    evaluate: Evaluate,
    samples: Minibatch,
    size: int,
    settings: LossSettings,
    *,
    at_a_time: int | None,
    parameters: Sequence[torch.Tensor],
) -> tuple[list[torch.Tensor | None], np.ndarray]:
    """`samples`' share of a `size`-sample minibatch's loss gradient with respect to
    `parameters` (None for one the loss does not reach), computed `at_a_time` samples at a
    time (None: all at once) and added slice by slice; their share of the `FIGURES`."""
    figures = np.zeros(len(FIGURES))
    gradients: list[torch.Tensor | None] = [None] * len(parameters)
    step = at_a_time or max(len(samples), 1)
    for start in range(0, len(samples), step):
        loss, piece_figures = slice_loss(
            evaluate, samples.part(start, start + step), size, settings
        )
        add_gradients(gradients, torch.autograd.grad(loss, parameters, allow_unused=True))
        figures += piece_figures
    return gradients, figures


def add_gradients(totals: list[torch.Tensor | None], pieces: Sequence[torch.Tensor | None]) -> None:
    """Add `pieces` (None: no gradient) into `totals`, parameter by parameter, in place."""
    for index, piece in enumerate(pieces):
        if piece is not None:
            total = totals[index]
            totals[index] = piece if total is None else total.add_(piece)

"""What a training's policy chose for some cars on one step, as PPO's rollout keeps it.

Plain numpy data, free of torch: a simulation process that acts for its own cars
(sim.training.actor) sends it to the trainer through a pipe, and the trainer joins the
parts' in the cars' order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Acting:
    """The policy's choice for each car's observation on one step."""

    pooled: Any  # the observations as the rollout buffer keeps them (camera frames pooled)
    actions: np.ndarray  # as sampled: a discrete action's index, or the Gaussian's draw
    values: np.ndarray  # the value of each observation, float32
    log_probs: np.ndarray  # the log-probability of each car's action
    # The value of the final observation of each car (index among these cars) whose
    # episode the step limit cut just before these observations: PPO bootstraps from it.
    final_values: dict[int, float] = field(default_factory=dict)

    def env_actions(self, discrete: bool) -> np.ndarray:
        """The actions as the cars take them: a continuous draw clipped to [-1, 1]."""
        if discrete:
            return self.actions
        clipped: np.ndarray = np.clip(self.actions, -1.0, 1.0).astype(np.float32)
        return clipped

    @classmethod
    def joined(cls, parts: list[Acting]) -> Acting:
        """Parts of a fleet (in the cars' order) as the whole fleet's."""
        if len(parts) == 1:
            return parts[0]
        finals: dict[int, float] = {}
        first = 0
        for part in parts:
            finals.update({first + car: value for car, value in part.final_values.items()})
            first += len(part.values)
        return cls(
            pooled=joined_observations([part.pooled for part in parts]),
            actions=np.concatenate([part.actions for part in parts]),
            values=np.concatenate([part.values for part in parts]),
            log_probs=np.concatenate([part.log_probs for part in parts]),
            final_values=finals,
        )


def joined_observations(parts: list[Any]) -> Any:
    """The parts' observations as one fleet's (a dict of arrays per sensor, or one array)."""
    if len(parts) == 1:
        return parts[0]
    if isinstance(parts[0], dict):
        return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
    return np.concatenate(parts)

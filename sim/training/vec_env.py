"""SB3's VecEnv interface over a training fleet of `sim.env.BatchedDeepRacer` cars.

`BatchedVecEnv` is many cars in one process: stepping 64 cars in one pymunk space costs
little more than one, so this is the fast path on a 2-core machine: no subprocesses, no
pickling, one batched observation per step. `sim.training.shards` spreads a fleet across
processes behind the same `FleetVecEnv` face. The trainer reads per-car details (status,
progress, steps) from `last_infos` rather than from SB3's info dicts.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from sim.env import BatchedDeepRacer, EnvConfig, StepInfo
from sim.training.acting import Acting
from sim.training.actor import PolicyActor


class FleetVecEnv(VecEnv):
    """N cars of one config as N SB3 environments with automatic resets; after each step
    `last_infos` holds every car's status, progress and steps.

    A training steps it with `act` and `step_and_act`: a fleet decides where its acting
    runs (sim.training.shards lets its simulation processes act for their cars)."""

    config: EnvConfig
    last_infos: list[StepInfo]
    # Every car's current observation (from `reset`, then each step), where this process
    # has them all.
    latest: Any = None

    def act(self, actor: PolicyActor) -> Acting:
        """Every car's action for the observation it stands at (after `reset`)."""
        return actor.act(self.latest)

    def step_and_act(
        self, acting: Acting, actor: PolicyActor
    ) -> tuple[np.ndarray, np.ndarray, Acting]:
        """Step every car with `acting`'s actions, then act on the new observations: the
        step's rewards (float32) and ends, and the acting for the next step (holding the
        values of the final observations where the step limit cut an episode)."""
        discrete = self.config.action_space.kind == "discrete"
        obs, rewards, dones, infos = self.step(acting.env_actions(discrete))
        finals = {
            car: infos[car]["terminal_observation"]
            for car in np.flatnonzero(dones).tolist()
            if infos[car]["TimeLimit.truncated"]
        }
        return rewards, dones, actor.act(obs, finals)

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        if attr_name == "render_mode":  # the cars are drawn by racer-tui, not by gymnasium
            return [None] * len(self._indices(indices))
        raise AttributeError(f"a training fleet has no per-car attribute {attr_name!r}")

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        raise AttributeError(f"a training fleet has no per-car attribute {attr_name!r}")

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        raise AttributeError(f"a training fleet's cars have no method {method_name!r}")

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return list(indices)


class BatchedVecEnv(FleetVecEnv):
    """N cars of one `BatchedDeepRacer`, in this process."""

    def __init__(self, config: EnvConfig, n_cars: int, seed: int | None = None) -> None:
        # `seed` seeds the cars' camera draws when the config randomises the camera.
        self.batch = BatchedDeepRacer(config, n_cars, seed)
        self.config = config
        super().__init__(n_cars, self.batch.observation_space, self.batch.action_space)
        self._actions: np.ndarray | None = None
        self.last_infos = []

    def reset(self) -> Any:
        self.latest = self.batch.reset()
        return self.latest

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        assert self._actions is not None, "step_async must come first"
        obs, rewards, terminated, truncated, infos = self.batch.step(self._actions)
        self.last_infos = infos
        dones = terminated | truncated
        infos_out = sb3_infos(dones, truncated, self.batch.final_observations)
        self.latest = obs
        return obs, rewards.astype(np.float32), dones, infos_out

    def close(self) -> None:
        """Nothing to release: the cars live in this process."""


def sb3_infos(
    dones: np.ndarray, truncated: np.ndarray, final_observations: Sequence[Any]
) -> list[dict[str, Any]]:
    """SB3's info dicts: a finished car's last observation, and whether the step limit cut
    its episode (then PPO bootstraps from its value there)."""
    infos: list[dict[str, Any]] = [{} for _ in range(len(dones))]
    for car in np.flatnonzero(dones).tolist():
        infos[car]["terminal_observation"] = final_observations[car]
        infos[car]["TimeLimit.truncated"] = bool(truncated[car])
    return infos

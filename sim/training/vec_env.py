"""SB3's VecEnv interface over `sim.env.BatchedDeepRacer`: many cars, one process.

Stepping 64 cars in one pymunk space costs little more than one, so this is the fast path
on a 2-core machine: no subprocesses, no pickling, one batched observation per step.
The trainer reads per-car details (status, progress, steps) from `last_infos` rather
than from SB3's info dicts.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from sim.env import BatchedDeepRacer, EnvConfig, StepInfo


class BatchedVecEnv(VecEnv):
    """N cars of one `BatchedDeepRacer` as N SB3 environments with automatic resets."""

    def __init__(self, config: EnvConfig, n_cars: int, seed: int | None = None) -> None:
        # `seed` seeds the cars' camera draws when the config randomises the camera.
        self.batch = BatchedDeepRacer(config, n_cars, seed)
        super().__init__(n_cars, self.batch.observation_space, self.batch.action_space)
        self._actions: np.ndarray | None = None
        self.last_infos: list[StepInfo] = []

    def reset(self) -> Any:
        return self.batch.reset()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        assert self._actions is not None, "step_async must come first"
        obs, rewards, terminated, truncated, infos = self.batch.step(self._actions)
        self.last_infos = infos
        dones = terminated | truncated
        sb3_infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for car in np.flatnonzero(dones).tolist():
            sb3_infos[car]["terminal_observation"] = self.batch.final_observations[car]
            sb3_infos[car]["TimeLimit.truncated"] = bool(truncated[car])
        return obs, rewards.astype(np.float32), dones, sb3_infos

    def close(self) -> None:
        """Nothing to release: the cars live in this process."""

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        if attr_name == "render_mode":  # the cars are drawn by racer-tui, not by gymnasium
            return [None] * len(self._indices(indices))
        return [getattr(self.batch, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.batch, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        result = getattr(self.batch, method_name)(*method_args, **method_kwargs)
        return [result] * len(self._indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return list(indices)

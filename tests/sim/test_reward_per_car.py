"""Every car has its own reward module, as every DeepRacer simulation worker has its own."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sim.env import BatchedDeepRacer, DeepRacerEnv, EnvConfig
from sim.reward.errors import RewardFunctionError
from sim.reward.function import load_reward_function
from tests.sim.shapes import rectangle_track

# Module-level state, as many community reward functions keep it: the previous call's steps.
STATEFUL = textwrap.dedent(
    """
    last = {"steps": None}


    def reward_function(params):
        steps = params["steps"]
        previous = last["steps"]
        # Each episode's first call is step 2 (step 1 is DeepRacer's prepare step).
        if previous is not None and steps not in (2, previous + 1):
            raise ValueError(f"steps went from {previous} to {steps}")
        last["steps"] = steps
        return 1.0
    """
)


@pytest.fixture
def stateful(tmp_path: Path) -> Path:
    path = tmp_path / "stateful.py"
    path.write_text(STATEFUL, encoding="utf-8")
    return path


def _drive(env: BatchedDeepRacer, steps: int) -> None:
    env.reset()
    actions = np.tile(np.array([[0.0, -0.6]], dtype=np.float32), (env.n, 1))
    for _ in range(steps):
        env.step(actions)


def test_a_stateful_reward_function_sees_only_its_own_cars_steps(stateful: Path) -> None:
    config = EnvConfig.build(rectangle_track(), reward=str(stateful))
    _drive(BatchedDeepRacer(config, 8), 40)


def test_one_module_shared_by_all_cars_would_break_it(stateful: Path) -> None:
    shared = load_reward_function(stateful)

    def one_module(params: Mapping[str, Any]) -> float:  # a plain callable: never copied
        return shared(params)

    config = EnvConfig.build(rectangle_track(), reward=one_module)
    with pytest.raises(RewardFunctionError, match="steps went from 3 to 3"):
        _drive(BatchedDeepRacer(config, 8), 40)


def test_fresh_copies_keep_their_own_module_state(stateful: Path) -> None:
    first = load_reward_function(stateful)
    second = first.fresh()
    params = {"steps": 2}
    first(params)
    first({"steps": 3})
    assert second(params) == 1.0  # its `last` was never touched by `first`
    assert second.name == first.name and second.source == first.source


def test_envs_built_from_one_config_do_not_share_a_module(stateful: Path) -> None:
    config = EnvConfig.build(rectangle_track(), reward=str(stateful))
    one, two = DeepRacerEnv(config), DeepRacerEnv(config)
    one.reset(options={"start": 0.0})
    two.reset(options={"start": 0.0})
    for _ in range(5):
        one.step(np.array([0.0, -0.6], dtype=np.float32))
        two.step(np.array([0.0, -0.6], dtype=np.float32))

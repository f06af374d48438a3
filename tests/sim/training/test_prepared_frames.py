"""The PPO update prepares a rollout's camera frames once (uint8 to float, channels first,
pooled) instead of for every minibatch of every epoch: the update it makes must be the
same to the bit, for a camera alone and for a camera beside the lidar."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import torch

from sim.training import ppo
from tests.sim.training.rollouts import collected


def _updated(sensors: tuple[str, ...], prepared: bool, monkeypatch: pytest.MonkeyPatch) -> Any:
    torch.manual_seed(3)
    np.random.seed(3)  # the minibatches' order (SB3 draws it from numpy's generator)
    model = collected(sensors, batch_size=16)
    if not prepared:

        @contextlib.contextmanager
        def as_before(*_: Any) -> Iterator[None]:
            yield

        monkeypatch.setattr(ppo, "_frames_prepared", as_before)
    np.random.seed(4)
    model.train()
    monkeypatch.undo()
    return {name: value.detach().clone() for name, value in model.network.state_dict().items()}


@pytest.mark.parametrize("sensors", [("camera",), ("camera", "lidar")])
def test_the_update_is_the_same_to_the_bit(
    sensors: tuple[str, ...], monkeypatch: pytest.MonkeyPatch
) -> None:
    before = _updated(sensors, prepared=False, monkeypatch=monkeypatch)
    after = _updated(sensors, prepared=True, monkeypatch=monkeypatch)
    assert before.keys() == after.keys()
    for name, value in before.items():
        assert torch.equal(value, after[name]), name
    # And the update moved the weights: the comparison compared something.
    untrained = collected(sensors, batch_size=16).network.state_dict()
    assert any(not torch.equal(untrained[name], value) for name, value in after.items())

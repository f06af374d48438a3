"""Checkpoints: network, optimizer and counters in one tensors-only file."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata
from sim.training.checkpoint import Progress, load_checkpoint, save_checkpoint
from sim.training.policy import PolicyError, build_network, save_policy

METADATA = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("vector",))


def _trained_pair() -> tuple[torch.nn.Module, torch.optim.Optimizer]:
    network = build_network(METADATA)
    optimizer = torch.optim.Adam(network.parameters(), lr=1e-3, eps=1e-5, foreach=True)
    params, values = network(torch.randn(8, 21))
    (params.sum() + values.sum()).backward()  # type: ignore[no-untyped-call]
    optimizer.step()
    return network, optimizer


def test_a_checkpoint_restores_weights_optimizer_and_counters(tmp_path: Path) -> None:
    network, optimizer = _trained_pair()
    progress = Progress(
        iteration=3,
        total_steps=4096,
        episodes=70,
        elapsed_seconds=12.5,
        best_progress=88.0,
        best_lap=None,
    )
    path = tmp_path / "latest.safetensors"
    save_checkpoint(path, network, optimizer, progress)  # type: ignore[arg-type]

    fresh = build_network(METADATA)
    fresh_optimizer = torch.optim.Adam(fresh.parameters(), lr=1e-3, eps=1e-5, foreach=True)
    assert load_checkpoint(path, fresh, fresh_optimizer) == progress
    for name, tensor in network.state_dict().items():
        assert torch.equal(tensor, fresh.state_dict()[name])
    before, after = optimizer.state_dict()["state"], fresh_optimizer.state_dict()["state"]
    assert before.keys() == after.keys()
    for index in before:
        assert torch.equal(before[index]["exp_avg_sq"], after[index]["exp_avg_sq"])
        assert float(before[index]["step"]) == float(after[index]["step"])


def test_a_policy_file_is_not_a_checkpoint(tmp_path: Path) -> None:
    path = tmp_path / "latest.safetensors"
    save_policy(path, build_network(METADATA))
    network = build_network(METADATA)
    with pytest.raises(PolicyError, match="not a training checkpoint"):
        load_checkpoint(path, network, torch.optim.Adam(network.parameters()))


def test_a_checkpoint_of_another_car_is_rejected(tmp_path: Path) -> None:
    network, optimizer = _trained_pair()
    path = tmp_path / "latest.safetensors"
    save_checkpoint(path, network, optimizer, Progress())  # type: ignore[arg-type]
    other = build_network(ModelMetadata(discrete_grid(30.0, 3, 3.0, 1), ("vector",)))
    with pytest.raises(PolicyError, match="different car"):
        load_checkpoint(path, other, torch.optim.Adam(other.parameters()))

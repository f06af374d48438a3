"""A training run in this process: where the weights come from, what it leaves behind."""

from __future__ import annotations

import json

import torch

from sim.garage.folder import ModelFolder
from sim.sensors.observations import SensorOptions
from sim.training import events
from sim.training.policy import build_network, load_policy, network_spec, save_policy
from sim.training.ppo import training_numerics
from sim.training.trainer import RunOptions, Trainer

TINY = RunOptions(minutes=5, cars=4, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)


def _run(model: ModelFolder, updates: int) -> list[events.Event]:
    stream: list[events.Event] = []

    def stop() -> bool:
        return sum(isinstance(e, events.Update) for e in stream) >= updates

    trainer = Trainer(model, stream.append, stop, TINY)
    stream.append(trainer.run())
    return stream


def test_a_clone_with_only_a_policy_starts_from_its_weights(model: ModelFolder) -> None:
    network = build_network(model.metadata())
    with torch.no_grad():
        network.value_head.bias.fill_(123.0)  # a mark training cannot erase in one update
    save_policy(model.policy_file, network)
    stream = _run(model, updates=1)
    started = stream[0]
    assert isinstance(started, events.Started) and started.resumed_from == "policy"
    ended = stream[-1]
    assert isinstance(ended, events.Ended) and ended.kind == "stopped"
    kept = load_policy(model.policy_file, model.metadata())
    assert abs(kept.value_head.bias.item() - 123.0) < 1.0


def test_a_stopped_run_leaves_state_metrics_and_a_checkpoint(model: ModelFolder) -> None:
    stream = _run(model, updates=2)
    assert [events.type_of(e) for e in stream].count("update") == 2
    state = json.loads(model.training_state_file.read_text())
    assert state["state"] == "stopped"
    assert set(state) >= {
        "state", "pid", "started_at", "updated_at", "elapsed_seconds", "steps", "episodes",
        "best_progress", "message",
    }  # fmt: skip
    assert (model.checkpoints_dir / "latest.safetensors").is_file()
    assert model.training_metrics_file.is_file() and model.has_policy()
    # The numerics it trained in, as this machine trains this network: recorded on the model.
    expected = training_numerics(network_spec(model.metadata(), SensorOptions()))
    assert state["numerics"] == expected == model.trained_numerics()
    again = _run(model, updates=1)
    started = again[0]
    assert isinstance(started, events.Started) and started.resumed_from == "checkpoint"
    assert started.total_steps == state["steps"]


def test_a_run_stopped_before_its_first_update_leaves_the_model_untrained(
    model: ModelFolder,
) -> None:
    stream = _run(model, updates=0)
    assert [events.type_of(e) for e in stream] == ["started", "stopped"]
    assert not model.has_policy()
    assert not (model.checkpoints_dir / "latest.safetensors").exists()
    assert json.loads(model.training_state_file.read_text())["state"] == "stopped"

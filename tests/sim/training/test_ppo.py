"""DeepRacer's PPO: hyperparameters mapped one to one, Huber value loss really used."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import torch
from torch.nn import functional

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata, default_hyperparameters
from sim.env import EnvConfig
from sim.training import ppo_loss
from sim.training.policy import network_spec
from sim.training.ppo import PPOSettings, RacerPPO, make_ppo
from sim.training.vec_env import BatchedVecEnv

METADATA = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("vector",))


def _model(loss_type: str = "huber", cars: int = 4) -> RacerPPO:
    hyperparameters = default_hyperparameters()
    hyperparameters.update(loss_type=loss_type, batch_size=32, num_epochs=3)
    config = EnvConfig.build("hairpin-circuit", METADATA.action_space, ("vector",))
    env = BatchedVecEnv(config, cars)
    settings = PPOSettings.from_hyperparameters(hyperparameters)
    model = make_ppo(env, network_spec(METADATA), settings, max_samples=256, seed=1)
    model.start_rollouts()
    return model


def test_deepracer_hyperparameters_map_onto_ppo() -> None:
    values = default_hyperparameters()
    values.update(
        batch_size=128,
        num_epochs=4,
        lr=0.0005,
        beta_entropy=0.02,
        discount_factor=0.99,
        num_episodes_between_training=30,
        loss_type="mean squared error",
    )
    settings = PPOSettings.from_hyperparameters(values)
    config = EnvConfig.build("hairpin-circuit", METADATA.action_space, ("vector",))
    model = make_ppo(BatchedVecEnv(config, 2), network_spec(METADATA), settings, max_samples=64)
    assert (model.batch_size, model.n_epochs, model.gamma, model.ent_coef) == (128, 4, 0.99, 0.02)
    assert model.learning_rate == 0.0005
    assert model.clip_range(1.0) == 0.2 and model.gae_lambda == 0.95
    assert model.policy.optimizer.defaults["eps"] == 1e-5
    assert model.loss_type == "mean squared error"
    assert settings.episodes_per_update == 30


def test_the_huber_value_loss_is_smooth_l1_not_mse() -> None:
    model = _model("huber")
    values, returns = torch.tensor([0.0, 0.0, 1.0]), torch.tensor([10.0, 0.5, 1.0])
    loss = model.value_loss(values, returns)
    assert torch.isclose(loss, functional.smooth_l1_loss(values, returns))
    assert not torch.isclose(loss, functional.mse_loss(values, returns))
    # Huber grows linearly for big errors: (9.5 + 0.125 + 0) / 3.
    assert loss.item() == pytest.approx((9.5 + 0.125) / 3)


@pytest.fixture
def loss_calls(monkeypatch: pytest.MonkeyPatch) -> Iterator[dict[str, int]]:
    """Counts the value-loss functions PPO's update really calls."""
    calls = {"smooth_l1_loss": 0, "mse_loss": 0}

    def counting(name: str) -> Any:
        original = getattr(functional, name)

        def wrapper(*args: Any, **kwargs: Any) -> torch.Tensor:
            calls[name] += 1
            return original(*args, **kwargs)  # type: ignore[no-any-return]

        return wrapper

    for name in calls:
        monkeypatch.setattr(ppo_loss.functional, name, counting(name))
    yield calls


@pytest.mark.parametrize(
    ("loss_type", "used", "unused"),
    [("huber", "smooth_l1_loss", "mse_loss"), ("mean squared error", "mse_loss", "smooth_l1_loss")],
)
def test_the_update_trains_the_value_function_with_the_chosen_loss(
    loss_calls: dict[str, int], loss_type: str, used: str, unused: str
) -> None:
    model = _model(loss_type)
    rollout = model.collect(episodes_wanted=1, min_samples=64, max_samples=128)
    model.train()
    minibatches = model.n_epochs * -(-rollout.steps // model.batch_size)
    assert loss_calls[used] == minibatches
    assert loss_calls[unused] == 0
    stats = model.last_update
    assert np.isfinite([stats.entropy, stats.policy_loss, stats.value_loss]).all()


def test_the_reported_value_loss_is_huber_of_values_and_returns() -> None:
    model = _model("huber")
    model.collect(episodes_wanted=1, min_samples=64, max_samples=64)
    buffer = model.rollout_buffer
    batch = next(buffer.get(None))  # the whole rollout, before any update
    with torch.no_grad():
        values = model.policy.predict_values(batch.observations).flatten()
    expected = functional.smooth_l1_loss(values, batch.returns).item()
    model.n_epochs, model.batch_size = 1, len(batch.returns)  # one step over the same batch
    model.train()
    assert model.last_update.value_loss == pytest.approx(expected, rel=1e-5)


def test_a_rollout_gathers_until_enough_episodes_have_finished() -> None:
    model = _model(cars=4)
    rollout = model.collect(episodes_wanted=3, min_samples=4, max_samples=4000)
    assert len(rollout.episodes) >= 3
    assert rollout.steps == model.rollout_buffer.buffer_size * 4
    assert rollout.steps < 4000  # it stopped early, on the episode count
    episode = rollout.episodes[0]
    assert episode.status != "In progress" and episode.steps > 0
    assert model.num_timesteps == rollout.steps


def test_a_rollout_stops_at_its_sample_cap() -> None:
    model = _model(cars=4)
    rollout = model.collect(episodes_wanted=10_000, min_samples=4, max_samples=40)
    assert rollout.steps == 40

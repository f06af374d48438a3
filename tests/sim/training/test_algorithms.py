"""A sac model is refused with one sentence, never trained as PPO."""

from __future__ import annotations

from dataclasses import replace

import pytest

from sim.deepracer.action_space import FULL_RANGE_CONTINUOUS, parse_action_space
from sim.deepracer.files import (
    default_hyperparameters,
    parse_hyperparameters,
    write_model_metadata,
)
from sim.garage.folder import ModelError, ModelFolder
from sim.training.ppo import PPOSettings
from sim.training.trainer import Trainer

DISCRETE = parse_action_space([{"steering_angle": 0.0, "speed": 1.0}])


def _as_sac(model: ModelFolder, continuous: bool) -> None:
    space = FULL_RANGE_CONTINUOUS if continuous else DISCRETE
    metadata = replace(model.metadata(), training_algorithm="sac", action_space=space)
    write_model_metadata(model.metadata_file, metadata)


@pytest.mark.parametrize(
    ("continuous", "message"),
    [
        (False, "training_algorithm sac needs a continuous action space"),
        (True, "racer-tui trains clipped_ppo models, not sac"),
    ],
)
def test_a_sac_model_is_refused_before_training(
    model: ModelFolder, continuous: bool, message: str
) -> None:
    _as_sac(model, continuous)
    with pytest.raises(ModelError, match=message) as caught:
        Trainer(model, lambda event: None, lambda: False)
    text = str(caught.value)
    assert text.endswith(".") and "\n" not in text
    assert not model.training_state_file.exists()


def test_a_clipped_ppo_model_is_accepted(model: ModelFolder) -> None:
    assert model.metadata().training_algorithm == "clipped_ppo"
    Trainer(model, lambda event: None, lambda: False)


def test_loss_type_defaults_as_deepracer() -> None:
    # The console writes huber into every hyperparameters.json (new models here too); a
    # file without loss_type trains as simapp trains it: mean squared error.
    assert default_hyperparameters()["loss_type"] == "huber"
    read = parse_hyperparameters('{"lr": 0.001}', "hyperparameters.json")
    assert read["loss_type"] == "mean squared error"
    assert PPOSettings.from_hyperparameters(read).loss_type == "mean squared error"
    huber = parse_hyperparameters('{"loss_type": "huber"}', "hyperparameters.json")
    assert PPOSettings.from_hyperparameters(huber).loss_type == "huber"

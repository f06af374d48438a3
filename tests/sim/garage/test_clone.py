"""Cloning: the clone starts from the trained policy, and only shape-compatible changes pass."""

from __future__ import annotations

import pytest

from sim.coach.reward_line import template_source
from sim.garage.clone import clone_model
from sim.garage.folder import ModelError, ModelFolder, ModelStatus, models_dir


def test_a_clone_carries_the_trained_policy(trained_model: ModelFolder) -> None:
    clone = clone_model(trained_model, "veteran-2")
    assert clone.policy_file.read_bytes() == trained_model.policy_file.read_bytes()
    assert clone.content_hash() == trained_model.content_hash()
    assert clone.metadata() == trained_model.metadata()
    assert clone.hyperparameters() == trained_model.hyperparameters()
    assert clone.training_params().extra["CLONED_FROM"] == "veteran"
    # A fresh training run: no evaluations or metrics of the source come along.
    assert clone.status() is ModelStatus.TRAINED
    assert clone.evaluation_files() == []


def test_reward_hyperparameters_and_speeds_may_change(trained_model: ModelFolder) -> None:
    clone = clone_model(
        trained_model,
        "faster",
        reward="stay_inside_borders",
        hyperparameters={"lr": 0.0001},
        max_speed=4.0,  # same 5 x 2 grid, so the same number of actions
        minutes=15,
        track="beginner-oval",
    )
    assert clone.reward_source() == template_source("stay_inside_borders")
    assert clone.hyperparameters()["lr"] == 0.0001
    assert clone.hyperparameters()["batch_size"] == trained_model.hyperparameters()["batch_size"]
    assert clone.metadata().action_space.max_speed == 4.0
    assert clone.training_params().max_minutes == 15
    assert clone.track().name == "beginner-oval"
    assert clone.has_policy()


@pytest.mark.parametrize(
    ("options", "problem"),
    [
        ({"sensors": ["lidar"]}, "the sensor changes from vector to lidar"),
        ({"steering_levels": 7}, "the number of actions changes from 10 to 14"),
        ({"continuous": True}, "the action space changes from discrete to continuous"),
    ],
)
def test_shape_changes_are_refused(
    trained_model: ModelFolder, options: dict[str, object], problem: str
) -> None:
    with pytest.raises(ModelError) as caught:
        clone_model(trained_model, "mutant", **options)
    assert problem in str(caught.value)
    assert "cannot start from 'veteran'" in str(caught.value)
    assert not (models_dir() / "mutant").exists()


def test_an_untrained_model_clones_with_any_change(model: ModelFolder) -> None:
    clone = clone_model(model, "lidar-rookie", sensors=["LIDAR"])
    assert clone.metadata().sensors == ("lidar",)
    assert not clone.has_policy()

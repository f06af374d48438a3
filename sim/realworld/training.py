"""Where a model's camera randomisation meets its training: the trainer's env config.

Only the trainer's environments draw perturbations; evaluations (the training's own and a
racer's) and races drive on the plain render, as the model's folder describes it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from sim.deepracer.files import TrainingParams
from sim.env import EnvConfig
from sim.realworld.settings import model_camera_randomisation

if TYPE_CHECKING:
    from sim.garage.folder import ModelFolder


def training_config(
    config: EnvConfig, params: TrainingParams, where: str = "training_params.yaml"
) -> EnvConfig:
    """`config` (a model's `env_config()`) with the camera randomisation its training
    params ask for; a bad key is a ModelError naming it."""
    settings = model_camera_randomisation(params, where)
    if settings == config.camera_randomisation:
        return config
    return replace(config, camera_randomisation=settings)


def folder_training_config(folder: ModelFolder) -> EnvConfig:
    """The env config a training of `folder` drives: the trainer's and each of its
    simulation processes' (sim.training.shards)."""
    return training_config(
        folder.env_config(), folder.training_params(), str(folder.training_params_file)
    )

"""The env config a model drives, built from its folder: the track, action space, sensors
and reward function, training_params.yaml's start-position and direction settings, the
objects of its race type, and for its training the camera randomisation it asks for.

A model folder only stores files; what a simulation needs of them is put together here.
Only the trainer's environments draw camera perturbations: evaluations and races drive
the plain render (`model_env_config`).
"""

from __future__ import annotations

from dataclasses import replace

from sim.deepracer.files import DeepRacerFileError, TrainingParams
from sim.env import EnvConfig
from sim.garage.folder import ModelError, ModelFolder, camera_randomisation_of
from sim.garage.options import blind_to_objects
from sim.physics.objects.reading import race_settings
from sim.physics.objects.settings import RaceSettings, RaceType
from sim.physics.simulation import EpisodeRules


def model_env_config(folder: ModelFolder) -> EnvConfig:
    """What a model's evaluations and races drive (the plain render)."""
    return _env_config(folder, folder.training_params())


def training_env_config(folder: ModelFolder) -> EnvConfig:
    """What a training of `folder` drives: the trainer's and each of its simulation
    processes' (sim.training.shards)."""
    params = folder.training_params()  # read once for both
    config = _env_config(folder, params)
    return training_config(config, params, str(folder.training_params_file))


def _env_config(folder: ModelFolder, params: TrainingParams) -> EnvConfig:
    metadata = folder.metadata()
    return EnvConfig(
        track=folder.track(),
        action_space=metadata.action_space,
        sensors=metadata.sensors,
        reward=folder.reward_function(),
        rules=EpisodeRules(
            change_start=params.change_start_position,
            alternate_direction=params.alternate_driving_direction,
        ),
        is_reversed=params.reverse_direction,
        race=_race(folder, params),
    )


def training_config(
    config: EnvConfig, params: TrainingParams, where: str = "training_params.yaml"
) -> EnvConfig:
    """`config` with the camera randomisation `params` ask for; a bad key is a ModelError
    naming it."""
    settings = camera_randomisation_of(params, where)
    if settings == config.camera_randomisation:
        return config
    return replace(config, camera_randomisation=settings)


def _race(folder: ModelFolder, params: TrainingParams) -> RaceSettings | None:
    """An object-avoidance model's boxes or a head-to-bot model's bot cars (None for a
    time trial); a model whose sensors cannot see them is refused in one sentence."""
    try:
        settings = race_settings(params, str(folder.training_params_file))
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None
    if settings.race_type is RaceType.TIME_TRIAL:
        return None
    blind = blind_to_objects(settings.race_type, folder.metadata().sensors)
    if blind is not None:
        raise ModelError(f"{folder.name} races {settings.race_type.words}, but {blind}")
    return settings

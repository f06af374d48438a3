"""A small model with one rollout collected, for tests of the PPO update."""

from __future__ import annotations

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata, default_hyperparameters
from sim.env import EnvConfig
from sim.training.policy import network_spec
from sim.training.ppo import PPOSettings, RacerPPO, make_ppo
from sim.training.vec_env import BatchedVecEnv

SAMPLES = 48


def collected(sensors: tuple[str, ...], batch_size: int, epochs: int = 2) -> RacerPPO:
    """Two cars on the hairpin circuit, 48 samples collected, ready to `train`."""
    metadata = ModelMetadata(discrete_grid(30.0, 3, 2.0, 1), sensors)
    hyperparameters = default_hyperparameters()
    hyperparameters.update(batch_size=batch_size, num_epochs=epochs)
    config = EnvConfig.build("hairpin-circuit", metadata.action_space, sensors)
    settings = PPOSettings.from_hyperparameters(hyperparameters)
    env = BatchedVecEnv(config, 2)
    model = make_ppo(env, network_spec(metadata), settings, max_samples=SAMPLES)
    model.start_rollouts()
    model.collect(episodes_wanted=100, min_samples=SAMPLES, max_samples=SAMPLES)
    return model

"""Which of DeepRacer's training algorithms racer-tui trains, and the one sentence when not.

A `model_metadata.json` names `clipped_ppo` or `sac`. DeepRacer trains SAC only with a
continuous action space (simapp `bundle/markov/multi_agent_coach/action_space_configs.py`,
`SACActionSpaceConfig`, refuses anything else). racer-tui trains clipped PPO; a SAC model is
refused with a sentence that says what to change, never quietly trained as PPO.
"""

from __future__ import annotations

from sim.deepracer.files import ModelMetadata
from sim.garage.folder import ModelError

TRAINED_ALGORITHMS = ("clipped_ppo",)


def check_trainable(metadata: ModelMetadata) -> None:
    """Raise `ModelError` (one sentence) unless racer-tui can train this model as written."""
    algorithm = metadata.training_algorithm
    if algorithm in TRAINED_ALGORITHMS:
        return
    if algorithm == "sac" and metadata.action_space.kind != "continuous":
        raise ModelError(
            "training_algorithm sac needs a continuous action space, as in the DeepRacer "
            "console; use clipped_ppo or a continuous action space in model_metadata.json."
        )
    raise ModelError(
        f"racer-tui trains clipped_ppo models, not {algorithm}; set training_algorithm to "
        "clipped_ppo in model_metadata.json to train this model with PPO."
    )

"""Why `model export --format droa` refuses: what DeepRacer on AWS needs to restore a model,
and what racer-tui cannot yet prove it gives.

DeepRacer on AWS imports a folder (`model_metadata.json`, `reward_function.py`,
`training_params.yaml`, `ip/hyperparameters.json` and `model/`), checks it with a model
validator whose code is not published (its image, `deepracer-on-aws-model-validation`, is
only named in the solution's templates), then trains or evaluates from `model/`: an
rl_coach TensorFlow checkpoint (`.coach_checkpoint`, `<n>_Step-<m>.ckpt.index`, `.data-*`,
`.meta`) restored into DeepRacer's own network for the model's sensor. racer-tui's
policies are its own networks, kept as safetensors. Writing such a checkpoint means
training with DeepRacer's exact network and naming every variable as DeepRacer's graph
does, then proving with TensorFlow that the checkpoint restores and that its frozen graph
acts as racer-tui's policy does. Until that proof exists here, the export is refused in
one sentence rather than written untested (docs/deepracer/deepracer-on-aws.md).
"""

from __future__ import annotations

from sim.garage.folder import ModelError

DROA_EXPORT_REFUSAL = (
    "racer-tui cannot write a model for DeepRacer on AWS to import: it restores only "
    "rl_coach TensorFlow checkpoints of DeepRacer's own network, and no racer-tui policy "
    "has been proven to restore into one (docs/deepracer/deepracer-on-aws.md says what "
    "is missing); export it for the car with --format car, or as a bundle, instead."
)


def refuse_droa_export() -> None:
    raise ModelError(DROA_EXPORT_REFUSAL)

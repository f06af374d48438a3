"""`racer-tui model act`: what a model would do with one camera picture, as the car runs it.

The picture is prepared as the car prepares its frames (`sim.car_export.frame`) and given to
the model: a car archive's graph (imported or a file), or racer-tui's own policy, whose
deterministic actor is exactly what the car archive export writes. The answer is the action
probabilities (discrete) or the mean (continuous), and the action the car takes, with its
servo and throttle (`sim.car_archive.car_mapping`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sim.car_archive.archive import read_car_archive
from sim.car_archive.car_mapping import CarAction, CarMapping, car_actions
from sim.car_export.frame import car_frame
from sim.deepracer.action_space import ActionSpace
from sim.garage.folder import ModelError, ModelFolder


@dataclass(frozen=True)
class ModelAnswer:
    """What a model does with one frame."""

    kind: str  # "discrete" or "continuous"
    outputs: tuple[float, ...]  # the probabilities of each action, or the mean (-1..1)
    action: CarAction  # the action the car takes, as it drives it
    frame_size: tuple[int, int]  # (width, height) the picture was prepared at
    actions: tuple[CarAction, ...]  # a discrete space's actions, as the car drives them


def answer(outputs: NDArray[np.float32], space: ActionSpace, size: tuple[int, int]) -> ModelAnswer:
    """The car's choice from one frame's graph output."""
    values = tuple(float(value) for value in np.asarray(outputs, dtype=np.float64).reshape(-1))
    mapping = CarMapping.of(space)
    if space.kind == "discrete":
        index = int(np.argmax(values))
        chosen = space.actions[index]
        action = mapping.action(chosen.steering_angle, chosen.speed, index)
    else:
        steering, speed = space.targets(np.array([values], dtype=np.float64))
        action = mapping.action(float(steering[0]), float(speed[0]))
    table = car_actions(space) if space.kind == "discrete" else ()
    return ModelAnswer(space.kind, values, action, size, table)


def archive_answer(path: Path, rgb: NDArray[np.uint8]) -> ModelAnswer:
    """What the car archive at `path` does with the picture."""
    from sim.car_archive.policy import CarPolicy  # noqa: PLC0415 (torch: only when the car acts)

    policy = CarPolicy(read_car_archive(path))
    frame = car_frame(rgb, policy.width, policy.height)
    outputs = policy.outputs(frame[np.newaxis])[0]
    return answer(outputs, policy.archive.metadata.action_space, (policy.width, policy.height))


def model_answer(folder_path: Path, rgb: NDArray[np.uint8]) -> ModelAnswer:
    """What the garage model in `folder_path` does with the picture."""
    import torch  # noqa: PLC0415 (torch: only when the car acts)

    from sim.training.policy import load_policy  # noqa: PLC0415 (torch: only when the car acts)

    folder = ModelFolder(folder_path)
    if folder.drives_with_car_archive():
        return archive_answer(folder.car_archive_file, rgb)
    metadata = folder.metadata()
    if metadata.sensors != ("camera",):
        raise ModelError(
            f"model {folder.name!r} senses {'+'.join(metadata.sensors)}; model act shows what "
            "a camera-only model does with a picture."
        )
    if not folder.has_policy():
        raise ModelError(
            f"model {folder.name!r} has no trained policy yet; train it first with "
            f"`racer-tui train {folder.name}`."
        )
    network = load_policy(folder.policy_file, metadata)
    height, width, _ = network.spec.input_shapes[0]
    frame = car_frame(rgb, width, height)
    obs = torch.from_numpy(frame[np.newaxis, :, :, np.newaxis].copy())
    with torch.inference_mode():
        params = network.action_parameters(network.features(obs))
    if metadata.action_space.kind == "discrete":
        outputs = torch.softmax(params, dim=1)[0].numpy()
    else:
        outputs = params.clamp(-1.0, 1.0)[0].numpy()
    return answer(outputs, metadata.action_space, (width, height))

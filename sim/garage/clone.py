"""Cloning a model, as in the DeepRacer console: a new model that starts from a trained one.

The clone gets the source's files and its trained policy, so training continues from
those weights. Options may change the clone (reward, hyperparameters, track, even the
action space or sensor) as long as the policy network keeps the same input and output
shapes; otherwise the weights could not be loaded, and the clone is refused.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from typing import Any

from sim.deepracer.files import ModelMetadata
from sim.garage.folder import POLICY_FILE, ModelError, ModelFolder
from sim.garage.options import create_from_spec, model_spec, spec_of


def clone_model(source: ModelFolder, name: str, **options: Any) -> ModelFolder:
    """Create `name` from `source` with `model_spec` options applied, copying its policy."""
    problem = source.car_archive_problem("clone")
    if problem is not None:
        raise ModelError(problem)
    base = spec_of(source)
    spec = model_spec(base, **options) if options else base
    if source.has_policy():
        check_compatible(source.metadata(), spec.metadata, source.name)
    return create_from_spec(
        name, spec, populate=_copy_policy_from(source), notes={"CLONED_FROM": source.name}
    )


def check_compatible(old: ModelMetadata, new: ModelMetadata, source_name: str) -> None:
    """ModelError unless a policy trained for `old` can drive a car described by `new`."""
    problem = incompatibility(old, new)
    if problem:
        raise ModelError(
            f"the clone cannot start from {source_name!r}'s trained policy because {problem}; "
            "keep those the same, or create a new model with `racer-tui model new`."
        )


def incompatibility(old: ModelMetadata, new: ModelMetadata) -> str:
    """Why the policy network's shapes would differ, or "" when they stay the same."""
    if old.sensors != new.sensors:
        return f"the sensor changes from {_names(old.sensors)} to {_names(new.sensors)}"
    if old.action_space.kind != new.action_space.kind:
        return f"the action space changes from {old.action_space.kind} to {new.action_space.kind}"
    old_count, new_count = len(old.action_space.actions), len(new.action_space.actions)
    if old_count != new_count:
        return f"the number of actions changes from {old_count} to {new_count}"
    if old.neural_network != new.neural_network:
        return f"the network changes from {old.neural_network} to {new.neural_network}"
    if old.training_algorithm != new.training_algorithm:
        return (
            f"the training algorithm changes from {old.training_algorithm} "
            f"to {new.training_algorithm}"
        )
    return ""


def _names(sensors: tuple[str, ...]) -> str:
    return "+".join(sensors)


def _copy_policy_from(source: ModelFolder) -> Callable[[ModelFolder], None]:
    def populate(target: ModelFolder) -> None:
        if source.has_policy():
            shutil.copyfile(source.policy_file, target.path / POLICY_FILE)

    return populate

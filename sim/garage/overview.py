"""What `model list` and `model show` say about a model, as plain JSON-ready data.

The CLI prints these as tables or JSON, and the TUI can show the same facts, so the
wording of a model's state lives in one place.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

from sim.car_archive.car_mapping import car_actions, car_refusal
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.car_look import CAR_LOOK_KEYS, car_look
from sim.deepracer.files import (
    DeepRacerFileError,
    EvaluationTrial,
    TrainingParams,
    read_evaluation_metrics,
)
from sim.garage.folder import ModelError, ModelFolder, model_folders
from sim.garage.summary import training_summary
from sim.physics.labels import CURRENT, DEEPRACER, describe
from sim.reward.template_files import template_name
from sim.sensors.randomisation.settings import read_camera_randomisation


def describe_actions(space: ActionSpace) -> str:
    """One short phrase: "10 discrete, up to 3 m/s" or "continuous -30..30 deg, 0.5..4 m/s"."""
    if space.kind == "discrete":
        return f"{len(space.actions)} discrete, up to {space.max_speed:g} m/s"
    (steer_low, steer_high), (speed_low, speed_high) = space.steering_range, space.speed_range
    return f"continuous {steer_low:g}..{steer_high:g} deg, {speed_low:g}..{speed_high:g} m/s"


def listing_signature() -> tuple[tuple[object, ...], ...]:
    """What a garage listing shows that can change outside the app showing it (a training
    the command line starts or that ends, new weights, an evaluation, an edited car): cheap
    enough to read every few seconds, where reading the listing itself is not."""
    return tuple(
        (
            folder.name,
            folder.is_training(),
            _changed_at(folder.policy_file),
            _changed_at(folder.metadata_file),
            _changed_at(folder.training_params_file),
            len(folder.evaluation_files()),
        )
        for folder in model_folders()
    )


def _changed_at(path: Path) -> int | None:
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


def model_row(folder: ModelFolder) -> dict[str, Any]:
    """One line of `model list`; a damaged folder still lists, with the problem as its status."""
    try:
        metadata = folder.metadata()
        params = folder.training_params()
        track = params.world_name
        best = folder.best_evaluation_lap()
        files = folder.evaluation_files()
        stale = bool(files) and folder.stale_evaluation(files[-1]) is not None
        status = str(folder.status())
    except ModelError as error:
        return {
            "name": folder.name,
            "status": "damaged",
            "problem": str(error),
            "track": None,
            "sensor": None,
            "actions": None,
            "best_lap_s": None,
            "evaluated_before_training": False,
            "race": None,
        }
    return {
        "name": folder.name,
        "status": status,
        "track": track,
        "race": race_words(params),
        "sensor": "+".join(metadata.sensors),
        "actions": describe_actions(metadata.action_space),
        "best_lap_s": best,
        # The latest evaluation is of the policy before the last training: a retrained
        # model's laps are not known until it is evaluated again.
        "evaluated_before_training": stale,
    }


def race_words(params: TrainingParams) -> str:
    """The race type as racers say it: "time trial", "object avoidance, 3 boxes (random)"."""
    kind = params.race_type.strip().upper()
    if kind == "OBJECT_AVOIDANCE":
        extra = params.extra
        boxes = extra.get("OBJECT_POSITIONS") or []
        count = (
            len(boxes) if isinstance(boxes, list) and boxes else extra.get("NUMBER_OF_OBSTACLES", 0)
        )
        random = str(extra.get("RANDOMIZE_OBSTACLE_LOCATIONS", False)).lower() == "true"
        return f"object avoidance, {count} boxes{' (random)' if random else ''}"
    if kind == "HEAD_TO_BOT":
        extra = params.extra
        lanes = str(extra.get("IS_LANE_CHANGE", False)).lower() == "true"
        speed = extra.get("BOT_CAR_SPEED", 0.2)
        return (
            f"head-to-bot, {extra.get('NUMBER_OF_BOT_CARS', 0)} bots at {speed} m/s"
            f"{' (changing lanes)' if lanes else ''}"
        )
    return "time trial"


def model_details(folder: ModelFolder) -> dict[str, Any]:
    """Everything `model show` prints: metadata, actions, hyperparameters, training, evaluations."""
    metadata = folder.metadata()
    params = folder.training_params()
    space = metadata.action_space
    evaluations: list[dict[str, Any]] = []
    for path in folder.evaluation_files():
        try:
            trials = folder_evaluation(folder, path.name)
        except ModelError as error:
            evaluations.append({"file": path.name, "problem": str(error), "trials": []})
            continue
        laps = [t.lap_time_seconds for t in trials if t.lap_time_seconds is not None]
        evaluations.append(
            {
                "file": path.name,
                "before_last_training": folder.stale_evaluation(path) is not None,
                "laps_completed": len(laps),
                "trials_run": len(trials),
                "best_lap_s": min(laps) if laps else None,
                "trials": [asdict(trial) for trial in trials],
            }
        )
    return {
        "name": folder.name,
        "path": str(folder.path),
        "status": str(folder.status()),
        "content_hash": folder.content_hash(),
        "track": params.world_name,
        "race": race_words(params),
        "track_hash": params.track_hash,
        "max_minutes": params.max_minutes,
        "sensor": "+".join(metadata.sensors),
        "actions_summary": describe_actions(space),
        "metadata": metadata.to_json(),
        "actions": _action_rows(space),
        "on_the_car": [asdict(action) for action in car_actions(space)],
        # An archive model's graph is the car's own, whatever trained it.
        "car_refusal": None if folder.drives_with_car_archive() else car_refusal(metadata),
        "car_archive": folder.drives_with_car_archive(),
        "camera_randomisation": _camera_randomisation_words(folder, params),
        "hyperparameters": folder.hyperparameters(),
        "reward_function": reward_origin(folder),
        "training": training_summary(folder),
        "evaluations": evaluations,
        # How the car looks in DeepRacer's simulator (DeepRacer on AWS keeps it): shown
        # as one phrase, not as its two keys among the notes.
        "car_look": look.describe() if (look := car_look(params.extra)) else None,
        "notes": {
            key: str(value) for key, value in params.extra.items() if key not in CAR_LOOK_KEYS
        },
        "physics_note": physics_note(folder.trained_physics()),
    }


def _camera_randomisation_words(folder: ModelFolder, params: TrainingParams) -> str:
    """What the model's training randomises of its camera, in words ("off" when nothing)."""

    try:
        return read_camera_randomisation(params, str(folder.training_params_file)).describe()
    except DeepRacerFileError as error:
        return str(error)


def physics_note(trained: str | None) -> str | None:
    """One sentence when the policy learnt another car than today's, else None."""

    if trained is None or trained == CURRENT:
        return None
    if trained == DEEPRACER:  # a car archive's weights: they cannot be trained here
        return (
            f"trained in {describe(DEEPRACER)}, whose car handles differently from "
            f"{describe(CURRENT)}: its laps here are not its laps there."
        )
    return (
        f"trained on {describe(trained)}; today's car is {describe(CURRENT)} and handles "
        "differently: train it again before racing (its old laps keep their own board)."
    )


def folder_evaluation(folder: ModelFolder, file_name: str) -> tuple[EvaluationTrial, ...]:
    """The trials of `metrics/<file_name>`, one of `folder.evaluation_files()`."""
    try:
        return read_evaluation_metrics(folder.metrics_dir / file_name)
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None


def reward_origin(folder: ModelFolder) -> str:
    """Which template the reward function is, or "custom"."""

    name = template_name(folder.reward_source())
    return "custom" if name is None else f"template {name}"


def _action_rows(space: ActionSpace) -> list[dict[str, Any]]:
    """The discrete action table (empty for a continuous space: its ranges are the metadata)."""
    return [
        {"index": i, "steering_angle": a.steering_angle, "speed": a.speed}
        for i, a in enumerate(space.actions)
    ]


_NETWORK_SIZES = {
    "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW": "shallow",
    "DEEP_CONVOLUTIONAL_NETWORK": "standard",
    "DEEP_CONVOLUTIONAL_NETWORK_DEEP": "deep",
}


def network_words(metadata: Mapping[str, Any]) -> str:
    """The network the model really has. DeepRacer's files name a convolutional network
    whatever the sensor; a model without a camera has no image to convolve, and racer-tui
    trains dense layers only, of the size the name says."""
    name = str(metadata.get("neural_network") or "-")
    sensors = metadata.get("sensor") or []
    if any("CAMERA" in str(sensor) for sensor in sensors) or name not in _NETWORK_SIZES:
        return name
    return f"dense, {_NETWORK_SIZES[name]} (no camera)"

"""The model editor's logic, without Textual: form text in, a checked `ModelSpec` out.

The editor screen collects what the racer typed as plain strings (`FormValues`); this module
turns them into the garage's `ModelSpec`, reporting every problem against the field it
belongs to (`FieldProblem`), so the screen can mark the field and keep everything the racer
typed. Saving goes through the garage library: `create_from_spec` for a new model, and
`save_edit` for an existing one (each file written atomically, after everything has been
checked, so a bad value never touches the model).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from sim.deepracer.action_space import ActionSpace, ActionSpaceError, discrete_grid
from sim.deepracer.files import (
    HYPERPARAMETER_SPECS,
    DeepRacerFileError,
    check_hyperparameters,
    write_hyperparameters,
    write_model_metadata,
    write_training_params,
)
from sim.deepracer.vocabulary import (
    MAX_SPEED,
    MAX_STEERING,
    MIN_SPEED,
    SensorError,
    normalise_sensors,
)
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.names import NAME_RULE, is_valid_name
from sim.foundation.remedies import Note, RemedyError, echoed
from sim.garage.clone import incompatibility
from sim.garage.folder import MAX_MINUTES, MIN_MINUTES, ModelError, ModelFolder, list_models
from sim.garage.options import (
    DEFAULT_BOT_SPEED,
    DEFAULT_BOTS,
    DEFAULT_OBSTACLES,
    RACE_KEYS,
    RACE_TYPES,
    SPEED_LEVELS,
    STEERING_LEVELS,
    ModelSpec,
    RaceOptions,
    blind_to_objects,
    create_from_spec,
    default_model_spec,
    racing_line_followed,
    with_race,
)
from sim.reward.errors import RewardFunctionError
from sim.reward.function import check_reward_code
from sim.sensors.randomisation.settings import (
    CameraRandomisation,
    parse_camera_randomisation,
    settings_text,
    with_camera_randomisation_keys,
)
from sim.tracks.catalog import resolve_track
from sim.tracks.track import TrackError

REWARD_FILE_NAME = "reward_function.py"
# The sensor choices the console offers, in racer-tui's names.
# DeepRacer's race types as the editor offers them: (label, RACE_TYPES key).
RACE_TYPE_CHOICES: tuple[tuple[str, str], ...] = (
    ("time trial", "time-trial"),
    ("object avoidance", "object-avoidance"),
    ("head-to-bot", "head-to-bot"),
)
SENSOR_CHOICES: tuple[tuple[str, str], ...] = (
    ("vector", "vector"),
    ("lidar", "LIDAR"),
    ("sector_lidar", "sector LIDAR"),
    ("camera", "camera"),
    ("camera+lidar", "camera + LIDAR"),
)
# Beside the sensor field, for the sensor chosen: what it is good for (a camera model's
# editor once said "vector trains fastest").
# Short: the select beside it keeps its room at 80 columns.
SENSOR_HINTS: dict[str, str] = {
    "vector": "fastest; sim only",
    "lidar": "sees boxes and cars",
    "sector_lidar": "LIDAR in sectors",
    "camera": "as a real car sees",
    "camera+lidar": "as a DeepRacer Evo",
}
DISCRETE, CONTINUOUS, KEPT = "discrete", "continuous", "kept"
TUNABLE = tuple(spec for spec in HYPERPARAMETER_SPECS.values() if spec.tunable)


@dataclass(frozen=True)
class FieldProblem:
    field: str  # the form field's id
    message: str  # one sentence saying what is allowed


def field_message(error: RemedyError) -> str:
    """A library error as a field's problem: a Note when it ends in a remedy, so the editor
    says the app's own remedy (`in_app_words`), never the command line's."""
    if error.fix is None:
        return str(error)
    return Note(str(error), problem=error.problem, fix=error.fix)


class FormError(RemedyError):
    """The form cannot be saved yet; `problems` says where and why."""

    def __init__(self, problems: list[FieldProblem]) -> None:
        self.problems = tuple(problems)
        super().__init__(problems[0].message if problems else "the form has a problem.")


@dataclass(frozen=True)
class FormValues:
    """What the editor's fields hold, as typed."""

    name: str
    track: str
    sensor: str
    action_kind: str  # DISCRETE, CONTINUOUS, or KEPT (an imported list left as it is)
    max_steering: str
    steering_levels: int
    max_speed: str
    speed_levels: int
    steering_low: str
    steering_high: str
    speed_low: str
    speed_high: str
    max_minutes: str
    reward_source: str
    hyperparameters: Mapping[str, str] = field(default_factory=dict)
    # DeepRacer's race type (a key of RACE_TYPES) and its objects: how many boxes or bot
    # cars, the bots' speed, and whether the boxes are shuffled / the bots change lanes.
    race_type: str = "time-trial"
    race_objects: str = str(DEFAULT_OBSTACLES)
    bot_speed: str = f"{DEFAULT_BOT_SPEED:g}"
    race_shuffle: bool = False
    # What a camera model's training randomises, as `parse_camera_randomisation` reads it.
    camera_randomisation: str = "off"

    @property
    def race(self) -> tuple[str, str, str, bool]:
        return (self.race_type, self.race_objects, self.bot_speed, self.race_shuffle)


def sensor_key(sensors: tuple[str, ...]) -> str:
    return "+".join(sensors)


def grid_of(space: ActionSpace) -> tuple[float, int, float, int] | None:
    """(max steering, steering levels, max speed, speed levels) if the console's generator
    makes exactly this action space, else None (an imported or hand-written list)."""
    if space.kind != DISCRETE:
        return None
    steers = sorted({action.steering_angle for action in space.actions})
    speeds = sorted({action.speed for action in space.actions})
    try:
        grid = (max(abs(s) for s in steers), len(steers), max(speeds), len(speeds))
        return grid if discrete_grid(*grid) == space else None
    except (ActionSpaceError, ValueError):
        return None


def values_of(spec: ModelSpec, name: str = "") -> FormValues:
    """The form filled in from a spec (the defaults, or a model being edited)."""
    space = spec.metadata.action_space
    grid = grid_of(space)
    kind = DISCRETE if grid is not None else KEPT
    if space.kind == CONTINUOUS:
        kind = CONTINUOUS
    default_grid = grid_of(default_model_spec().metadata.action_space)
    assert default_grid is not None
    steer, steer_levels, speed, speed_levels = grid or default_grid
    (steer_low, steer_high), (speed_low, speed_high) = space.steering_range, space.speed_range
    race = _race_values(spec)
    return FormValues(
        name=name,
        track=spec.track,
        sensor=sensor_key(spec.metadata.sensors),
        action_kind=kind,
        max_steering=f"{steer:g}",
        steering_levels=steer_levels,
        max_speed=f"{speed:g}",
        speed_levels=speed_levels,
        steering_low=f"{steer_low:g}",
        steering_high=f"{steer_high:g}",
        speed_low=f"{speed_low:g}",
        speed_high=f"{speed_high:g}",
        max_minutes=f"{spec.max_minutes:g}",
        reward_source=spec.reward_source,
        hyperparameters={
            hp.name: str(spec.hyperparameters.get(hp.name, hp.default)) for hp in TUNABLE
        },
        race_type=race[0],
        race_objects=race[1],
        bot_speed=race[2],
        race_shuffle=race[3],
        camera_randomisation=settings_text(spec.camera_randomisation),
    )


def _race_values(spec: ModelSpec) -> tuple[str, str, str, bool]:
    """The race type's fields of the form (type, objects, bot speed, shuffle), from
    DeepRacer's keys."""
    keys = spec.race_keys
    kind = {value: key for key, value in RACE_TYPES.items()}.get(
        spec.race_type.strip().upper(), "time-trial"
    )
    speed = f"{DEFAULT_BOT_SPEED:g}"
    if kind == "head-to-bot":
        return (
            kind,
            str(keys.get("NUMBER_OF_BOT_CARS", DEFAULT_BOTS)),
            str(keys.get("BOT_CAR_SPEED", speed)),
            str(keys.get("IS_LANE_CHANGE", False)).lower() == "true",
        )
    if kind == "object-avoidance":
        positions = keys.get("OBJECT_POSITIONS")
        count = len(positions) if isinstance(positions, list) and positions else None
        return (
            kind,
            str(count or keys.get("NUMBER_OF_OBSTACLES", DEFAULT_OBSTACLES)),
            speed,
            str(keys.get("RANDOMIZE_OBSTACLE_LOCATIONS", False)).lower() == "true",
        )
    return (kind, str(DEFAULT_OBSTACLES), speed, False)


def _with_race_of_form(
    spec: ModelSpec, values: FormValues, base: ModelSpec, problems: list[FieldProblem]
) -> ModelSpec:
    """`spec` with the form's race type; the base model's own keys (an imported model's
    OBJECT_POSITIONS, say) are kept as they are while the racer leaves the fields alone."""
    if values.race == values_of(base).race:
        return spec
    if values.race_type == "time-trial":
        return replace(spec, race_type="TIME_TRIAL", race_keys={})
    count = _number(values.race_objects)
    whole = None if count is None or count != int(count) else int(count)
    if whole is None:
        problems.append(FieldProblem("race-objects", "Give a whole number of boxes or bot cars."))
        return spec
    bots = values.race_type == "head-to-bot"
    speed = _number(values.bot_speed) if bots else None
    if bots and speed is None:
        problems.append(FieldProblem("bot-speed", "The bots' speed must be a number of m/s."))
        return spec
    options = (
        RaceOptions(bots=whole, bot_speed=speed, bot_lane_change=values.race_shuffle)
        if bots
        else RaceOptions(obstacles=whole, randomize_obstacles=values.race_shuffle)
    )
    try:
        return with_race(spec, values.race_type, options)
    except ModelError as error:
        where = "bot-speed" if "--bot-speed" in str(error) else "race-objects"
        message = str(error).replace("--obstacles", "Boxes").replace("--bots", "Bot cars")
        problems.append(FieldProblem(where, message.replace("--bot-speed", "The bots' speed")))
        return spec


# --- checking ---------------------------------------------------------------------------


def _number(text: str) -> float | None:
    try:
        value = float(text.strip())
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _in_range(
    problems: list[FieldProblem],
    field_id: str,
    text: str,
    label: str,
    limits: tuple[float, float],
) -> float:
    low, high = limits
    value = _number(text)
    if value is None or not low <= value <= high:
        problems.append(
            FieldProblem(field_id, f"{label} must be a number from {low:g} to {high:g}.")
        )
        return math.nan
    return value


def action_space_of(values: FormValues, kept: ActionSpace | None = None) -> ActionSpace:
    """The action space the form describes; FormError names the field at fault.

    `kept` is the model's own discrete list, used when the racer leaves it as it is."""
    problems: list[FieldProblem] = []
    if values.action_kind == KEPT:
        if kept is None:
            raise FormError([FieldProblem("action-kind", "Choose discrete or continuous.")])
        return kept
    if values.action_kind == CONTINUOUS:
        limits = (-MAX_STEERING, MAX_STEERING)
        lo = _in_range(problems, "steering-low", values.steering_low, "Lowest steering", limits)
        hi = _in_range(problems, "steering-high", values.steering_high, "Highest steering", limits)
        slo = _in_range(
            problems, "speed-low", values.speed_low, "Lowest speed", (MIN_SPEED, MAX_SPEED)
        )
        shi = _in_range(
            problems, "speed-high", values.speed_high, "Highest speed", (MIN_SPEED, MAX_SPEED)
        )
        if not problems and lo >= hi:
            problems.append(
                FieldProblem("steering-high", "Highest steering must be above lowest steering.")
            )
        if not problems and slo >= shi:
            problems.append(FieldProblem("speed-high", "Highest speed must be above lowest speed."))
        if problems:
            raise FormError(problems)
        return ActionSpace(kind="continuous", steering_range=(lo, hi), speed_range=(slo, shi))
    steer = _in_range(
        problems, "max-steering", values.max_steering, "Maximum steering", (1.0, MAX_STEERING)
    )
    speed = _in_range(
        problems, "max-speed", values.max_speed, "Maximum speed", (MIN_SPEED, MAX_SPEED)
    )
    if values.steering_levels not in STEERING_LEVELS:
        problems.append(FieldProblem("steering-levels", "Steering levels must be 3, 5 or 7."))
    if values.speed_levels not in SPEED_LEVELS:
        problems.append(FieldProblem("speed-levels", "Speed levels must be 1, 2 or 3."))
    if problems:
        raise FormError(problems)
    return discrete_grid(steer, values.steering_levels, speed, values.speed_levels)


def check_name(name: str, taken: set[str]) -> str | None:
    """A problem with a new model's name (`taken`: existing names, case-folded), or None."""
    if not name:
        return "Give the model a name."
    if not is_valid_name(name):
        return f"{echoed(name)} cannot be a model name; use {NAME_RULE}."
    if name.casefold() in taken:
        return f"A model named {name!r} already exists; choose another name."
    return None


def taken_names() -> set[str]:
    return {folder.name.casefold() for folder in list_models()}


def reward_problem(source: str) -> RewardFunctionError | None:
    """Why the reward function code is not a reward function (with its line), or None:
    checked without running it, in the app's own process (Check, ctrl+r, runs it in a
    child process with a time limit)."""
    try:
        check_reward_code(source, REWARD_FILE_NAME)
    except RewardFunctionError as error:
        return error
    return None


def spec_of_form(
    values: FormValues,
    *,
    base: ModelSpec,
    new_name_taken: set[str] | None = None,
    kept: ActionSpace | None = None,
) -> ModelSpec:
    """The checked spec; FormError lists every field at fault.

    `base` supplies what the form does not show (the non-tunable hyperparameters, the
    network); `new_name_taken` is given when the name is new and must be free."""

    problems: list[FieldProblem] = []
    if new_name_taken is not None:
        name_problem = check_name(values.name.strip(), new_name_taken)
        if name_problem:
            problems.append(FieldProblem("name", name_problem))
    try:
        resolve_track(values.track)
    except TrackError as error:
        problems.append(FieldProblem("track", field_message(error)))
    sensors: tuple[str, ...] = base.metadata.sensors
    try:
        sensors = normalise_sensors(values.sensor.split("+"))
    except SensorError as error:
        problems.append(FieldProblem("sensor", str(error)))
    space = base.metadata.action_space
    try:
        space = action_space_of(values, kept)
    except FormError as error:
        problems.extend(error.problems)
    hyperparameters = _hyperparameters(values.hyperparameters, base, problems)
    minutes = _number(values.max_minutes)
    if minutes is None or not MIN_MINUTES <= minutes <= MAX_MINUTES:
        problems.append(
            FieldProblem(
                "max-minutes",
                f"The training time limit must be from {MIN_MINUTES:g} to {MAX_MINUTES:g} minutes.",
            )
        )
    reward = reward_problem(values.reward_source)
    if reward is not None:
        problems.append(FieldProblem("reward", str(reward)))
    randomisation = CameraRandomisation.OFF
    try:
        randomisation = parse_camera_randomisation(values.camera_randomisation)
    except ValueError as error:
        problems.append(FieldProblem("camera-randomisation", _sentence(str(error))))
    if randomisation.on and "camera" not in sensors:
        problems.append(
            FieldProblem(
                "camera-randomisation",
                "Camera randomisation needs a camera: choose the camera sensor, or write off.",
            )
        )
    raced = _with_race_of_form(base, values, base, problems)
    blind = blind_to_objects(raced.race_type, sensors)
    if blind is not None:
        problems.append(FieldProblem("sensor", blind[0].upper() + blind[1:]))
    if problems:
        raise FormError(problems)
    metadata = replace(base.metadata, action_space=space, sensors=sensors)
    spec = replace(
        raced,
        track=values.track,
        metadata=metadata,
        hyperparameters=hyperparameters,
        reward_source=values.reward_source,
        reward_origin="editor",
        max_minutes=float(values.max_minutes),
        camera_randomisation=randomisation,
    )
    return racing_line_followed(spec, base)


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


def _hyperparameters(
    texts: Mapping[str, str], base: ModelSpec, problems: list[FieldProblem]
) -> dict[str, float | int | str]:
    typed: dict[str, object] = {}
    for spec in TUNABLE:
        text = texts.get(spec.name, str(spec.default)).strip()
        if spec.choices:
            typed[spec.name] = text
            continue
        value = _number(text)
        if value is None or spec.low is None or spec.high is None:
            problems.append(
                FieldProblem(f"hp-{spec.name}", f"{spec.name} must be {spec.allowed()}.")
            )
            continue
        typed[spec.name] = value
    checked = dict(base.hyperparameters)
    for name, typed_value in typed.items():
        try:
            checked.update(check_hyperparameters({name: typed_value}, where="", base={}))
        except DeepRacerFileError:
            spec = HYPERPARAMETER_SPECS[name]
            problems.append(FieldProblem(f"hp-{name}", f"{name} must be {spec.allowed()}."))
    return checked


# --- saving -----------------------------------------------------------------------------


def create_from_form(name: str, spec: ModelSpec) -> ModelFolder:
    """A new garage model (the garage writes it whole, then renames it into place)."""
    return create_from_spec(name, spec)


def save_edit(folder: ModelFolder, spec: ModelSpec) -> ModelFolder:
    """Write an edited spec over an existing model, after checking all of it.

    A trained policy is kept, so its network's shape must not change (the same check as a
    clone); while a trainer runs, the files are left alone. Each file is replaced
    atomically, so the folder always holds a readable model."""

    if folder.is_training():
        raise ModelError(
            f"model {folder.name!r} is training right now; stop the training, then edit it."
        )
    metadata = spec.metadata
    if folder.drives_with_car_archive() and metadata != folder.metadata():
        raise ModelError(
            f"{folder.name!r} drives with a DeepRacer car archive, whose graph was made for its "
            "sensor, network and action space: keep them as they are (change its track, race "
            "type or time limit)."
        )
    if folder.has_policy():
        problem = incompatibility(folder.metadata(), metadata)
        if problem:
            raise ModelError(
                f"{folder.name!r} is trained, and its policy cannot drive the edited car because "
                f"{problem}; clone the model (c in the garage) to change those."
            )
    try:
        hyperparameters = check_hyperparameters(spec.hyperparameters, where="hyperparameters")
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None
    track = resolve_track(spec.track)
    check_reward_code(spec.reward_source, REWARD_FILE_NAME)
    before = folder.training_params()
    # The race type's and the camera randomisation's keys are the spec's; every other key
    # the file holds stays.
    extra = {key: value for key, value in before.extra.items() if key not in RACE_KEYS}
    extra = with_camera_randomisation_keys(extra, spec.camera_randomisation)
    params = replace(
        before,
        world_name=track.name,
        track_hash=track.content_hash,
        max_minutes=float(spec.max_minutes),
        race_type=spec.race_type,
        extra={**extra, **dict(spec.race_keys)},
    )
    write_bytes_atomic(folder.reward_file, spec.reward_source.encode("utf-8"))
    write_hyperparameters(folder.hyperparameters_file, hyperparameters)
    write_training_params(folder.training_params_file, params)
    write_model_metadata(folder.metadata_file, metadata)
    return folder

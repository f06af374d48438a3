"""A new model from console-style options, as the AWS DeepRacer console builds one.

The defaults live here, together, as named constants: `racer-tui model new`, the training
benchmark and the TUI all start from `default_model_spec()`. Every option is validated
before anything is written, and each error names the option and what it allows.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from sim.deepracer.action_space import (
    ActionSpace,
    ActionSpaceError,
    discrete_grid,
    parse_action_space,
)
from sim.deepracer.files import (
    HYPERPARAMETER_SPECS,
    DeepRacerFileError,
    ModelMetadata,
    check_hyperparameters,
    default_hyperparameters,
)
from sim.deepracer.vocabulary import (
    MAX_SPEED,
    MAX_STEERING,
    MIN_SPEED,
    SensorError,
    normalise_sensors,
)
from sim.garage.folder import (
    MAX_MINUTES,
    MIN_MINUTES,
    ModelError,
    ModelFolder,
    camera_randomisation_of,
    create_model,
)
from sim.physics.objects.settings import (
    MAX_BOT_CARS,
    MAX_BOT_SPEED,
    BotSettings,
    ObstacleSettings,
    race_keys,
)
from sim.reward.function import check_reward_code, read_reward_file
from sim.reward.template_files import TEMPLATES, shipped_template
from sim.sensors.randomisation.settings import CameraRandomisation, camera_randomisation_keys
from sim.tracks.catalog import DEFAULT_TRACK as CATALOG_DEFAULT_TRACK
from sim.tracks.catalog import resolve_track
from sim.tracks.track import TrackError

# --- the defaults of `racer-tui model new` (the Training helper benchmarks these) --------
# re:Invent 2018, the track of the league rule (sim.tracks.catalog says why).
DEFAULT_TRACK = CATALOG_DEFAULT_TRACK
# How many actions --actions-from-line clusters by default: the console's default grid has 10.
LINE_ACTIONS = 10
DEFAULT_SENSORS: tuple[str, ...] = ("vector",)
DEFAULT_MAX_STEERING = 30.0
DEFAULT_STEERING_LEVELS = 5
DEFAULT_MAX_SPEED = 3.0
DEFAULT_SPEED_LEVELS = 2
DEFAULT_REWARD = "follow_center_line"
DEFAULT_MINUTES = 60.0
# DeepRacer's defaults except two, both inside its ranges: batch 64 x 10 epochs spends most of a
# 2-core CPU on gradient steps (1-3k env steps/s); 512 x 4 trains at 5k+ steps/s and reaches
# 5/5 laps as quickly (measured by benchmarks.training.train).
DEFAULT_HYPERPARAMETER_CHANGES: dict[str, float | int | str] = {"batch_size": 512, "num_epochs": 4}


def default_model_hyperparameters() -> dict[str, float | int | str]:
    return {**default_hyperparameters(), **DEFAULT_HYPERPARAMETER_CHANGES}


STEERING_LEVELS = (3, 5, 7)
SPEED_LEVELS = (1, 2, 3)
MAX_ACTIONS_FILE_BYTES = 1_000_000


@dataclass(frozen=True)
class ModelSpec:
    """Everything a new model folder is made from, validated."""

    track: str
    metadata: ModelMetadata
    hyperparameters: dict[str, float | int | str] = field(
        default_factory=default_model_hyperparameters
    )
    reward_source: str = ""
    reward_origin: str = DEFAULT_REWARD  # a template name or the file it was read from
    max_minutes: float = DEFAULT_MINUTES
    race_type: str = "TIME_TRIAL"  # DeepRacer's RACE_TYPE
    race_keys: Mapping[str, object] = field(default_factory=dict)  # its settings' keys
    # Camera randomisation while training (sim.sensors.randomisation): camera models only.
    camera_randomisation: CameraRandomisation = CameraRandomisation.OFF


def default_action_space() -> ActionSpace:
    return discrete_grid(
        DEFAULT_MAX_STEERING, DEFAULT_STEERING_LEVELS, DEFAULT_MAX_SPEED, DEFAULT_SPEED_LEVELS
    )


def default_model_spec() -> ModelSpec:
    """The model `racer-tui model new NAME` makes without options."""
    return ModelSpec(
        track=DEFAULT_TRACK,
        metadata=ModelMetadata(default_action_space(), DEFAULT_SENSORS),
        reward_source=shipped_template(DEFAULT_REWARD),
    )


def model_spec(
    base: ModelSpec | None = None,
    *,
    track: str | None = None,
    sensors: Sequence[str] | None = None,
    max_steering: float | None = None,
    steering_levels: int | None = None,
    max_speed: float | None = None,
    speed_levels: int | None = None,
    actions_file: Path | None = None,
    continuous: bool = False,
    steering_range: tuple[float, float] | None = None,
    speed_range: tuple[float, float] | None = None,
    actions_from_line: int | None = None,
    reward: str | None = None,
    hyperparameters: Mapping[str, object] | None = None,
    minutes: float | None = None,
    race_type: str | None = None,
    obstacles: int | None = None,
    randomize_obstacles: bool = False,
    bots: int | None = None,
    bot_speed: float | None = None,
    bot_lane_change: bool = False,
    camera_randomisation: CameraRandomisation | None = None,
) -> ModelSpec:
    """`base` (default: `default_model_spec()`) with the given console options applied.

    The action space comes from exactly one of: the grid options (max steering, steering
    levels, max speed, speed levels; unset ones take the defaults), an actions file,
    `continuous` with optional ranges, or `actions_from_line` (that many actions clustered
    from the track's limit lap). With none of them, `base`'s action space is kept.
    A racing_line reward follows the model's track and action space when either changes.
    `camera_randomisation` (None: `base`'s) needs a camera sensor; one kept from `base`
    is dropped when the sensors change to ones without a camera.
    """
    before = base or default_model_spec()
    spec = before
    if track is not None:
        spec = replace(spec, track=_checked_track(track))
    metadata = spec.metadata
    if sensors is not None:
        try:
            metadata = replace(metadata, sensors=normalise_sensors(list(sensors)))
        except SensorError as error:
            raise ModelError(f"--sensor: {error}") from None
    grid = (max_steering, steering_levels, max_speed, speed_levels)
    space = _action_space(
        grid,
        actions_file,
        continuous=continuous,
        ranges=(steering_range, speed_range),
        from_line=None if actions_from_line is None else (spec.track, actions_from_line),
    )
    if space is not None:
        metadata = replace(metadata, action_space=space)
    spec = replace(spec, metadata=metadata)
    if reward is not None:
        source, origin = reward_choice(reward, spec.track, metadata.action_space)
        spec = replace(spec, reward_source=source, reward_origin=origin)
    else:
        spec = racing_line_followed(spec, before)
    if hyperparameters:
        try:
            checked = check_hyperparameters(
                hyperparameters, where="--hp", base=spec.hyperparameters
            )
        except DeepRacerFileError as error:
            raise ModelError(str(error)) from None
        spec = replace(spec, hyperparameters=checked)
    race_options = RaceOptions(obstacles, randomize_obstacles, bots, bot_speed, bot_lane_change)
    if race_type is not None or race_options.given:
        spec = with_race(spec, race_type, race_options)
    blind = blind_to_objects(spec.race_type, spec.metadata.sensors)
    if blind is not None:
        raise ModelError(f"--sensor: {blind}")
    spec = with_camera_randomisation(spec, camera_randomisation)
    if minutes is not None:
        if not (math.isfinite(minutes) and MIN_MINUTES <= minutes <= MAX_MINUTES):
            raise ModelError(
                f"--minutes must be from {MIN_MINUTES:g} to {MAX_MINUTES:g}, not {minutes:g}."
            )
        spec = replace(spec, max_minutes=float(minutes))
    return spec


def new_model(name: str, spec: ModelSpec | None = None, **options: Any) -> ModelFolder:
    """Create model `name` from `spec` (default: the defaults) with `model_spec` options."""
    chosen = model_spec(spec, **options) if options or spec is None else spec
    return create_from_spec(name, chosen)


def create_from_spec(name: str, spec: ModelSpec, **create_options: Any) -> ModelFolder:
    return create_model(
        name,
        track=spec.track,
        metadata=spec.metadata,
        hyperparameters=spec.hyperparameters,
        reward_source=spec.reward_source,
        max_minutes=spec.max_minutes,
        race_type=spec.race_type,
        race_keys={**spec.race_keys, **camera_randomisation_keys(spec.camera_randomisation)},
        **create_options,
    )


def spec_of(folder: ModelFolder) -> ModelSpec:
    """An existing model's spec, the base for a clone."""
    params = folder.training_params()
    return ModelSpec(
        track=params.world_name,
        metadata=folder.metadata(),
        hyperparameters=folder.hyperparameters(),
        reward_source=folder.reward_source(),
        reward_origin=str(folder.reward_file),
        max_minutes=params.max_minutes,
        race_type=params.race_type,
        race_keys={key: value for key, value in params.extra.items() if key in RACE_KEYS},
        camera_randomisation=camera_randomisation_of(params, str(folder.training_params_file)),
    )


def with_camera_randomisation(spec: ModelSpec, chosen: CameraRandomisation | None) -> ModelSpec:
    """`spec` training with `chosen` camera randomisation (None: keep its own, dropped when
    its sensors have no camera); ModelError when a model without a camera asks for it."""
    has_camera = "camera" in spec.metadata.sensors
    if chosen is None:
        if spec.camera_randomisation.on and not has_camera:
            return replace(spec, camera_randomisation=CameraRandomisation.OFF)
        return spec
    if chosen.on and not has_camera:
        raise ModelError(
            "camera randomisation needs a camera: choose the camera sensor, or leave it off."
        )
    return replace(spec, camera_randomisation=chosen)


# --- single options ------------------------------------------------------------------------


def _checked_track(track: str) -> str:

    try:
        resolve_track(track)
    except TrackError as error:
        raise ModelError(f"--track: {error}") from None
    return track


# The race types `model new --race-type` makes, by the names racers type.
RACE_TYPES = {
    "time-trial": "TIME_TRIAL",
    "object-avoidance": "OBJECT_AVOIDANCE",
    "head-to-bot": "HEAD_TO_BOT",
}
DEFAULT_OBSTACLES = 3  # the console's default for an object-avoidance model
MAX_OBSTACLES = 10
RACE_KEYS = frozenset(
    {
        "NUMBER_OF_OBSTACLES",
        "MIN_DISTANCE_BETWEEN_OBSTACLES",
        "RANDOMIZE_OBSTACLE_LOCATIONS",
        "OBSTACLE_TYPE",
        "IS_OBSTACLE_BOT_CAR",
        "OBJECT_POSITIONS",
        "NUMBER_OF_BOT_CARS",
        "MIN_DISTANCE_BETWEEN_BOT_CARS",
        "RANDOMIZE_BOT_CAR_LOCATIONS",
        "BOT_CAR_SPEED",
        "IS_LANE_CHANGE",
        "LOWER_LANE_CHANGE_TIME",
        "UPPER_LANE_CHANGE_TIME",
        "LANE_CHANGE_DISTANCE",
        "PENALTY_SECONDS",
    }
)
DEFAULT_BOTS = 3  # the console's default for a head-to-bot model
DEFAULT_BOT_SPEED = 1.0  # m/s


def blind_to_objects(race_type: str, sensors: Sequence[str]) -> str | None:
    """Why a model of `race_type` with `sensors` could not see its boxes or bots, or None."""
    if race_type.strip().upper() not in ("OBJECT_AVOIDANCE", "HEAD_TO_BOT"):
        return None
    if any(sensor in ("camera", "lidar", "sector_lidar") for sensor in sensors):
        return None
    return (
        "a model that races among objects needs a camera or a lidar: racer-tui's vector "
        "state does not show them."
    )


@dataclass(frozen=True)
class RaceOptions:
    """`model new`'s (and the editor's) options for the objects of a race type."""

    obstacles: int | None = None
    randomize_obstacles: bool = False
    bots: int | None = None
    bot_speed: float | None = None
    bot_lane_change: bool = False

    @property
    def for_boxes(self) -> bool:
        return self.obstacles is not None or self.randomize_obstacles

    @property
    def for_bots(self) -> bool:
        return self.bots is not None or self.bot_speed is not None or self.bot_lane_change

    @property
    def given(self) -> bool:
        return self.for_boxes or self.for_bots


def with_race(spec: ModelSpec, race_type: str | None, options: RaceOptions) -> ModelSpec:
    """`spec` racing `race_type` (a name of RACE_TYPES; without one, the type the object
    options belong to)."""

    default = "head-to-bot" if options.for_bots else "object-avoidance"
    chosen = race_type if race_type is not None else default
    if chosen not in RACE_TYPES:
        raise ModelError(f"--race-type must be one of {', '.join(RACE_TYPES)}, not {chosen!r}.")
    if options.for_boxes and chosen != "object-avoidance":
        raise ModelError("--obstacles and --randomize-obstacles need --race-type object-avoidance.")
    if options.for_bots and chosen != "head-to-bot":
        raise ModelError("--bots, --bot-speed and --bot-lane-change need --race-type head-to-bot.")
    if chosen == "time-trial":
        return replace(spec, race_type="TIME_TRIAL", race_keys={})
    if chosen == "head-to-bot":
        count = DEFAULT_BOTS if options.bots is None else options.bots
        if not 1 <= count <= MAX_BOT_CARS:
            raise ModelError(f"--bots must be from 1 to {MAX_BOT_CARS}, not {count}.")
        speed = DEFAULT_BOT_SPEED if options.bot_speed is None else options.bot_speed
        if not (math.isfinite(speed) and 0.1 <= speed <= MAX_BOT_SPEED):
            raise ModelError(
                f"--bot-speed must be from 0.1 to {MAX_BOT_SPEED:g} m/s, not {speed:g}."
            )
        settings = BotSettings(count=count, speed=speed, lane_change=options.bot_lane_change)
        return replace(spec, race_type=RACE_TYPES[chosen], race_keys=race_keys(settings))
    count = DEFAULT_OBSTACLES if options.obstacles is None else options.obstacles
    if not 1 <= count <= MAX_OBSTACLES:
        raise ModelError(f"--obstacles must be from 1 to {MAX_OBSTACLES}, not {count}.")
    boxes = ObstacleSettings(count=count, randomize=options.randomize_obstacles)
    return replace(spec, race_type=RACE_TYPES[chosen], race_keys=race_keys(boxes))


def reward_choice(
    reward: str, track: str = DEFAULT_TRACK, space: ActionSpace | None = None
) -> tuple[str, str]:
    """(source, origin) for a template name (racing_line with the line of `track` within
    `space`'s actions) or a reward function file, checked without running it (it runs when
    the racer trains or checks it)."""
    from sim.coach.reward_line import template_source  # noqa: PLC0415 (numpy, scipy: a template's line)

    if reward in TEMPLATES:
        return template_source(reward, track, space), reward
    path = Path(reward).expanduser()
    if not path.exists():
        raise ModelError(
            f"--reward: {reward!r} is neither a template ({', '.join(TEMPLATES)}) nor a file."
        )
    source = read_reward_file(path)
    check_reward_code(source, str(path))  # RewardFunctionError names the file and line
    return source, str(path)


def parse_hp_assignments(assignments: Sequence[str]) -> dict[str, object]:
    """`KEY=VALUE` strings from the command line, typed by each key's spec."""
    values: dict[str, object] = {}
    for assignment in assignments:
        key, sep, text = assignment.partition("=")
        key, text = key.strip(), text.strip()
        if not sep or not key:
            raise ModelError(f"--hp {assignment!r}: write KEY=VALUE, for example --hp lr=0.0003.")
        spec = HYPERPARAMETER_SPECS.get(key)
        if spec is None or spec.choices:
            values[key] = text  # unknown keys are reported by check_hyperparameters
            continue
        try:
            values[key] = float(text)
        except ValueError:
            raise ModelError(f"--hp: {key} must be {spec.allowed()}, not {text!r}.") from None
    return values


def parse_range(text: str, option: str, low: float, high: float, unit: str) -> tuple[float, float]:
    """`LOW,HIGH` for --steering-range and --speed-range."""
    parts = text.split(",")
    try:
        lo, hi = (float(part) for part in parts)
    except ValueError:
        lo = hi = math.nan
    if not (math.isfinite(lo) and math.isfinite(hi) and low <= lo < hi <= high):
        raise ModelError(
            f"{option} must be LOW,HIGH in {unit} with {low:g} <= LOW < HIGH <= {high:g}, "
            f"not {text!r}."
        )
    return lo, hi


def _action_space(
    grid: tuple[float | None, int | None, float | None, int | None],
    actions_file: Path | None,
    *,
    continuous: bool,
    ranges: tuple[tuple[float, float] | None, tuple[float, float] | None],
    from_line: tuple[str, int] | None = None,
) -> ActionSpace | None:
    uses_grid = any(value is not None for value in grid)
    uses_ranges = any(value is not None for value in ranges)
    chosen = [
        name
        for name, used in (
            ("--max-steering/--steering-levels/--max-speed/--speed-levels", uses_grid),
            ("--actions", actions_file is not None),
            ("--continuous", continuous),
            ("--actions-from-line", from_line is not None),
        )
        if used
    ]
    if len(chosen) > 1:
        raise ModelError(f"choose one way to give the action space, not {' and '.join(chosen)}.")
    if uses_ranges and not continuous:
        raise ModelError("--steering-range and --speed-range need --continuous.")
    if uses_grid:
        return _grid(*grid)
    if actions_file is not None:
        return read_actions_file(actions_file)
    if from_line is not None:
        return _line_actions(*from_line)
    if continuous:
        steering, speed = ranges
        return ActionSpace(
            kind="continuous",
            steering_range=steering or (-MAX_STEERING, MAX_STEERING),
            speed_range=speed or (MIN_SPEED, MAX_SPEED),
        )
    return None


def _grid(
    max_steering: float | None,
    steering_levels: int | None,
    max_speed: float | None,
    speed_levels: int | None,
) -> ActionSpace:
    steer = DEFAULT_MAX_STEERING if max_steering is None else max_steering
    steer_levels = DEFAULT_STEERING_LEVELS if steering_levels is None else steering_levels
    speed = DEFAULT_MAX_SPEED if max_speed is None else max_speed
    levels = DEFAULT_SPEED_LEVELS if speed_levels is None else speed_levels
    if not (math.isfinite(steer) and 1.0 <= steer <= MAX_STEERING):
        raise ModelError(
            f"--max-steering must be from 1 to {MAX_STEERING:g} degrees, not {steer:g}."
        )
    if steer_levels not in STEERING_LEVELS:
        raise ModelError(f"--steering-levels must be 3, 5 or 7, not {steer_levels}.")
    if not (math.isfinite(speed) and MIN_SPEED <= speed <= MAX_SPEED):
        raise ModelError(
            f"--max-speed must be from {MIN_SPEED:g} to {MAX_SPEED:g} m/s, not {speed:g}."
        )
    if levels not in SPEED_LEVELS:
        raise ModelError(f"--speed-levels must be 1, 2 or 3, not {levels}.")
    return discrete_grid(steer, steer_levels, speed, levels)


def _line_actions(track: str, count: int) -> ActionSpace:
    from sim.coach.line_actions import LineActionsError, actions_from_line  # noqa: PLC0415 (numpy and scipy: only for actions from a line)

    try:
        return actions_from_line(resolve_track(track), count)
    except LineActionsError as error:
        raise ModelError(f"--actions-from-line: {error}") from None


def racing_line_followed(spec: ModelSpec, before: ModelSpec) -> ModelSpec:
    """`spec` with a racing_line reward's line redrawn when its track or actions changed
    from `before`'s (only the template as racer-tui wrote it; see `line_followed`)."""
    was = (before.track, before.metadata.action_space)
    now = (spec.track, spec.metadata.action_space)
    if was == now:
        return spec  # before the coach's imports: most specs keep their track and actions
    from sim.coach.reward_line import line_followed  # noqa: PLC0415 (numpy and scipy: only when the line moves)

    source = line_followed(spec.reward_source, was, now)
    return spec if source == spec.reward_source else replace(spec, reward_source=source)


def read_actions_file(path: Path) -> ActionSpace:
    """A JSON action list, or any JSON object with an `action_space` (a model_metadata.json)."""
    try:
        if path.stat().st_size > MAX_ACTIONS_FILE_BYTES:
            raise ModelError(f"--actions: {path} is larger than 1 MB; is it an action list?")
        data: Any = json.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise ModelError(f"--actions: {path} does not exist.") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        raise ModelError(f"--actions: {path} is not a readable JSON file.") from None
    kind = None
    if isinstance(data, dict) and "action_space" in data:
        kind = data.get("action_space_type")
        data = data["action_space"]
    try:
        return parse_action_space(data, kind if isinstance(kind, str) else None)
    except ActionSpaceError as error:
        raise ModelError(f"--actions: {path}: {error}") from None

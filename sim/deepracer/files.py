"""The one place that knows AWS DeepRacer's file formats.

Model folders, the league's submission assembler, model import and the race engine all
read and write these files through this module, so a DeepRacer user's downloads and our
own folders are the same thing:

- `model_metadata.json`: action space, sensors, network, algorithm, version;
- `hyperparameters.json`: DeepRacer's keys, defaults and allowed ranges;
- `training_params.yaml`: the training job (track, race type, stop condition);
- training metrics (DeepRacer's TrainingMetrics form);
- evaluation metrics (DeepRacer's EvaluationMetrics form);
- sim-trace CSV files with DeepRacer's column names;
- where they sit in a model folder: deepracer-for-cloud's single-worker layout, the one
  deepracer-utils' `DeepRacerLog(folder)` detects (`model/`, `ip/`, `metrics/`,
  `training-simtrace/`, `evaluation-<stamp>/evaluation-simtrace/`), and where the AWS
  console's log downloads put them.

Files read here may come from anyone: every value is type- and range-checked, and every
problem is one `DeepRacerFileError` sentence that names the file.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import MISSING, asdict, dataclass, field, fields, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml
from numpy.typing import NDArray

from sim.deepracer.action_space import ActionSpace, ActionSpaceError, parse_action_space
from sim.deepracer.vocabulary import EpisodeStatus, SensorError, is_physics, normalise_sensors
from sim.foundation.atomic import write_text_atomic
from sim.foundation.remedies import RemedyError

MODEL_METADATA = "model_metadata.json"
HYPERPARAMETERS = "hyperparameters.json"
TRAINING_PARAMS = "training_params.yaml"
REWARD_FUNCTION = "reward_function.py"

# A model folder in deepracer-for-cloud's single-worker layout (paths inside the folder).
# DRfC keeps reward_function.py and training_params.yaml at the top of the model prefix.
MODEL_METADATA_PATH = f"model/{MODEL_METADATA}"
HYPERPARAMETERS_PATH = f"ip/{HYPERPARAMETERS}"
TRAINING_METRICS_PATH = "metrics/TrainingMetrics.json"
EVALUATION_METRICS_GLOB = "metrics/EvaluationMetrics-*.json"
TRAINING_SIMTRACE_DIR = "training-simtrace"
TRAINING_SIMTRACE_GLOB = f"{TRAINING_SIMTRACE_DIR}/*-iteration.csv"
EVALUATION_SIMTRACE_GLOB = "evaluation-*/evaluation-simtrace/0-iteration.csv"

# racer-tui's own layout before it followed DRfC's; `sim.garage.migrate` moves them.
LEGACY_TRAINING_METRICS = "training.json"
LEGACY_EVALUATION_GLOB = "evaluation-*.json"
LEGACY_SIM_TRACE_DIR = "sim-trace"

MAX_METADATA_BYTES = 1_000_000
MAX_METRICS_BYTES = 64_000_000
# Training metrics hold one row per episode of every car: far more than DeepRacer's one car
# writes in the same time (about 60 MB per hour of training with the vector sensor).
MAX_TRAINING_METRICS_BYTES = 512_000_000


class DeepRacerFileError(RemedyError):
    """A DeepRacer file that is missing or malformed; the message names the file."""


# --- hyperparameters -------------------------------------------------------------------


@dataclass(frozen=True)
class Hyperparameter:
    """One DeepRacer hyperparameter: its default and what values are allowed."""

    name: str
    default: float | int | str
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    whole: bool = False
    tunable: bool = True  # shown in the console's form; the rest are fixed by DeepRacer
    help: str = ""

    def allowed(self) -> str:
        if self.choices:
            return " or ".join(repr(choice) for choice in self.choices)
        kind = "a whole number" if self.whole else "a number"
        return f"{kind} from {self.low:g} to {self.high:g}"

    def check(self, value: object, where: str) -> float | int | str:
        """The value as stored, or DeepRacerFileError saying what is allowed."""
        problem = f"{where}: {self.name} must be {self.allowed()}, not {value!r}."
        if self.choices:
            if not isinstance(value, str) or value not in self.choices:
                raise DeepRacerFileError(problem)
            return value
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise DeepRacerFileError(problem)
        if not math.isfinite(value) or self.low is None or self.high is None:
            raise DeepRacerFileError(problem)
        if not self.low <= value <= self.high:
            raise DeepRacerFileError(problem)
        if self.whole:
            if float(value) != int(value):
                raise DeepRacerFileError(problem)
            return int(value)
        return float(value)


_HYPERPARAMETERS = (
    Hyperparameter("batch_size", 64, 32, 512, whole=True, help="experiences per gradient step"),
    Hyperparameter("beta_entropy", 0.01, 0.0, 1.0, help="entropy bonus: more exploration"),
    Hyperparameter("discount_factor", 0.999, 0.0, 1.0, help="how far ahead rewards count"),
    Hyperparameter("loss_type", "huber", choices=("huber", "mean squared error")),
    Hyperparameter("lr", 0.0003, 1e-8, 1e-3, help="learning rate"),
    Hyperparameter(
        "num_episodes_between_training", 20, 5, 100, whole=True, help="episodes per update"
    ),
    Hyperparameter("num_epochs", 10, 3, 10, whole=True, help="passes over each batch"),
    Hyperparameter("e_greedy_value", 0.05, 0.0, 1.0, tunable=False),
    Hyperparameter("epsilon_steps", 10000, 0, 10_000_000, whole=True, tunable=False),
    Hyperparameter(
        "exploration_type", "categorical", choices=("categorical", "e-greedy"), tunable=False
    ),
    Hyperparameter("stack_size", 1, 1, 1, whole=True, tunable=False),
    Hyperparameter("term_cond_avg_score", 100000.0, 0.0, 1e9, tunable=False),
    Hyperparameter("term_cond_max_episodes", 100000, 1, 10_000_000, whole=True, tunable=False),
    Hyperparameter("sac_alpha", 0.2, 0.0, 1.0, tunable=False),
)
HYPERPARAMETER_SPECS: dict[str, Hyperparameter] = {hp.name: hp for hp in _HYPERPARAMETERS}
# Fixed PPO internals DeepRacer does not expose.
PPO_CLIP = 0.2
GAE_LAMBDA = 0.95
ADAM_EPSILON = 1e-5


def default_hyperparameters() -> dict[str, float | int | str]:
    return {hp.name: hp.default for hp in _HYPERPARAMETERS}


def check_hyperparameters(
    values: Mapping[str, object],
    where: str = HYPERPARAMETERS,
    base: Mapping[str, float | int | str] | None = None,
) -> dict[str, float | int | str]:
    """Validated hyperparameters: `values` over `base` (DeepRacer's defaults if None)."""
    result = dict(default_hyperparameters() if base is None else base)
    for name, value in values.items():
        spec = HYPERPARAMETER_SPECS.get(str(name))
        if spec is None:
            known = ", ".join(hp.name for hp in _HYPERPARAMETERS if hp.tunable)
            raise DeepRacerFileError(
                f"{where}: unknown hyperparameter {name!r}; the tunable ones are {known}."
            )
        result[spec.name] = spec.check(value, where)
    return result


def read_hyperparameters(path: Path) -> dict[str, float | int | str]:
    return parse_hyperparameters(_read_text(path, MAX_METADATA_BYTES), str(path))


# What DeepRacer's simulator trains with when hyperparameters.json has no loss_type
# (simapp `bundle/markov/sagemaker_graph_manager.py`, `get_updated_hyper_parameters`); the
# console's form writes huber into every file it makes, and so do new models here.
SIMAPP_LOSS_TYPE = "mean squared error"


def parse_hyperparameters(text: str, where: str) -> dict[str, float | int | str]:
    """`hyperparameters.json` text (from a file, a zip member...); `where` names it in errors.

    A key the file leaves out takes the value DeepRacer's simulator would use."""
    base = {**default_hyperparameters(), "loss_type": SIMAPP_LOSS_TYPE}
    return check_hyperparameters(parse_json_object(text, where), where=where, base=base)


def write_hyperparameters(path: Path, values: Mapping[str, float | int | str]) -> None:
    write_text_atomic(path, json.dumps(dict(values), indent=2) + "\n")


# --- model metadata --------------------------------------------------------------------

SENSOR_FILE_NAMES = {
    "camera": "FRONT_FACING_CAMERA",
    "lidar": "LIDAR",
    "sector_lidar": "SECTOR_LIDAR",
    "vector": "VECTOR",  # racer-tui's own track-relative sensor; DeepRacer has no such name
}
NEURAL_NETWORKS = (
    "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW",
    "DEEP_CONVOLUTIONAL_NETWORK",
    "DEEP_CONVOLUTIONAL_NETWORK_DEEP",
)
TRAINING_ALGORITHMS = ("clipped_ppo", "sac")
METADATA_VERSION = "5"


@dataclass(frozen=True)
class ModelMetadata:
    """`model_metadata.json`: what the car can do and what it senses."""

    action_space: ActionSpace
    sensors: tuple[str, ...]  # racer-tui names: camera, lidar, sector_lidar, vector
    neural_network: str = NEURAL_NETWORKS[0]
    training_algorithm: str = "clipped_ppo"
    version: str = METADATA_VERSION

    @property
    def simapp_version(self) -> float:
        """The simulator version DeepRacer runs this model in: simapp reads `version` as a
        number, and a file without one as 1.0 or 2.0 (both older than any version racer-tui
        tells apart: `sim.physics.car.car_for_simapp_version`)."""
        try:
            return float(self.version)
        except ValueError:
            return 2.0

    def to_json(self) -> dict[str, Any]:
        return {
            "action_space": self.action_space.to_metadata(),
            "sensor": [SENSOR_FILE_NAMES[name] for name in self.sensors],
            "neural_network": self.neural_network,
            "training_algorithm": self.training_algorithm,
            "action_space_type": self.action_space.kind,
            "version": self.version,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], where: str = MODEL_METADATA) -> ModelMetadata:
        if "action_space" not in data:
            raise DeepRacerFileError(f"{where}: there is no action_space; add one.")
        try:
            space = parse_action_space(data["action_space"], data.get("action_space_type"))
        except ActionSpaceError as error:
            raise DeepRacerFileError(f"{where}: {error}") from None
        raw_sensors = data.get("sensor", ["FRONT_FACING_CAMERA"])
        if not isinstance(raw_sensors, list) or not all(isinstance(s, str) for s in raw_sensors):
            raise DeepRacerFileError(f"{where}: sensor must be a list of sensor names.")
        try:
            sensors = normalise_sensors(raw_sensors)
        except SensorError as error:
            raise DeepRacerFileError(f"{where}: {error}") from None
        network = str(data.get("neural_network", NEURAL_NETWORKS[0]))
        if network not in NEURAL_NETWORKS:
            raise DeepRacerFileError(
                f"{where}: unknown neural_network {network!r}; use one of "
                f"{', '.join(NEURAL_NETWORKS)}."
            )
        algorithm = str(data.get("training_algorithm", "clipped_ppo"))
        if algorithm not in TRAINING_ALGORITHMS:
            raise DeepRacerFileError(
                f"{where}: training_algorithm must be clipped_ppo or sac, not {algorithm!r}."
            )
        return cls(space, sensors, network, algorithm, str(data.get("version", "")))


def read_model_metadata(path: Path) -> ModelMetadata:
    return parse_model_metadata(_read_text(path, MAX_METADATA_BYTES), str(path))


def parse_model_metadata(text: str, where: str) -> ModelMetadata:
    return ModelMetadata.from_json(parse_json_object(text, where), where)


def write_model_metadata(path: Path, metadata: ModelMetadata) -> None:
    write_text_atomic(path, json.dumps(metadata.to_json(), indent=2) + "\n")


# --- training_params.yaml --------------------------------------------------------------


@dataclass(frozen=True)
class TrainingParams:
    """`training_params.yaml`: the training job, in DeepRacer's upper-case keys."""

    world_name: str  # the track
    race_type: str = "TIME_TRIAL"
    max_minutes: float = 60.0  # the console's stop condition
    alternate_driving_direction: bool = False
    change_start_position: bool = True
    reverse_direction: bool = False  # REVERSE_DIR: train the track the other way round
    track_hash: str = ""  # content hash of the track the model was set up on
    extra: Mapping[str, Any] = field(default_factory=dict)  # keys we keep but do not use

    _KEYS = {  # noqa: RUF012 - a constant mapping, not a field
        "WORLD_NAME": "world_name",
        "RACE_TYPE": "race_type",
        "MAX_MINUTES": "max_minutes",
        "ALTERNATE_DRIVING_DIRECTION": "alternate_driving_direction",
        "CHANGE_START_POSITION": "change_start_position",
        "REVERSE_DIR": "reverse_direction",
        "TRACK_HASH": "track_hash",
    }

    def to_yaml(self) -> str:
        data: dict[str, Any] = {"JOB_TYPE": "TRAINING", **dict(self.extra)}
        for key, attribute in self._KEYS.items():
            data[key] = getattr(self, attribute)
        return yaml.safe_dump(data, sort_keys=True)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str) -> TrainingParams:
        world = data.get("WORLD_NAME")
        if not isinstance(world, str) or not world:
            raise DeepRacerFileError(f"{where}: WORLD_NAME (the track) is missing.")
        minutes = data.get("MAX_MINUTES", 60.0)
        if (
            isinstance(minutes, bool)
            or not isinstance(minutes, int | float)
            or not (0 < minutes <= 100_000)
        ):
            raise DeepRacerFileError(f"{where}: MAX_MINUTES must be a positive number.")
        extra = {str(k): v for k, v in data.items() if k not in cls._KEYS and k != "JOB_TYPE"}
        return cls(
            world_name=world,
            race_type=str(data.get("RACE_TYPE", "TIME_TRIAL")),
            max_minutes=float(minutes),
            alternate_driving_direction=read_flag(
                data, "ALTERNATE_DRIVING_DIRECTION", False, where
            ),
            change_start_position=read_flag(data, "CHANGE_START_POSITION", True, where),
            reverse_direction=read_flag(data, "REVERSE_DIR", False, where),
            track_hash=str(data.get("TRACK_HASH", "")),
            extra=extra,
        )


def read_flag(data: Mapping[str, Any], key: str, default: bool, where: str) -> bool:
    """A yes/no setting; DeepRacer's tools write them as YAML booleans or as the strings
    "true"/"false" (simapp reads both, `markov/utils.py` str2bool)."""
    value = data.get(key, default)
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in ("true", "false"):
        return value.strip().lower() == "true"
    raise DeepRacerFileError(f"{where}: {key} must be true or false, not {value!r}.")


def read_training_params(path: Path) -> TrainingParams:
    return parse_training_params(_read_text(path, MAX_METADATA_BYTES), str(path))


def parse_training_params(text: str, where: str) -> TrainingParams:
    """`training_params.yaml` text: safe_load only, a job description is data, never objects."""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError:
        raise DeepRacerFileError(f"{where}: not valid YAML; fix the syntax.") from None
    if not isinstance(data, Mapping):
        raise DeepRacerFileError(f"{where}: expected a mapping of KEY: value lines.")
    return TrainingParams.from_mapping(data, where)


def write_training_params(path: Path, params: TrainingParams) -> None:
    write_text_atomic(path, params.to_yaml())


# --- training and evaluation metrics ---------------------------------------------------

METRIC_STATUSES = tuple(status.value for status in EpisodeStatus)


@dataclass(frozen=True)
class TrainingEpisode:
    """One row of DeepRacer's TrainingMetrics: an episode of training or of evaluation."""

    reward_score: float
    metric_time: int  # ms since the job started, when the episode ended
    start_time: int
    elapsed_time_in_milliseconds: int
    episode: int
    trial: int
    phase: str  # "training" or "evaluation"
    completion_percentage: float
    episode_status: str


@dataclass(frozen=True)
class EvaluationTrial:
    """One row of DeepRacer's EvaluationMetrics: a trial, normally one lap."""

    completion_percentage: float
    metric_time: int
    start_time: int
    elapsed_time_in_milliseconds: int  # penalty time is inside the elapsed time
    episode_status: str
    crash_count: int = 0
    immobilized_count: int = 0
    off_track_count: int = 0
    reversed_count: int = 0
    reset_count: int = 0
    trial: int = 1

    @property
    def lap_time_seconds(self) -> float | None:
        """The lap time if the trial completed the lap, else None."""
        if self.completion_percentage >= 100 and self.episode_status != "Off track":
            return self.elapsed_time_in_milliseconds / 1000.0
        return None


@dataclass(frozen=True)
class SimTraceSample:
    """How much of a training the sim-trace files hold. Kept in TrainingMetrics.json beside
    DeepRacer's keys (DeepRacer's readers ignore keys they do not know), so a sampled trace
    says so where the episodes are counted."""

    episodes: int  # training episodes that finished
    traced_episodes: int  # of those, the episodes whose every step is in training-simtrace/
    traced_steps: int
    rule: str = ""  # which episodes are traced, in words

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class TrainingMetrics:
    episodes: tuple[TrainingEpisode, ...]
    best_model_metric: str = "progress"
    version: float = 2.0
    sim_trace: SimTraceSample | None = None

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "metrics": [_metric_dict(e) for e in self.episodes],
            "version": self.version,
            "best_model_metric": self.best_model_metric,
        }
        if self.sim_trace is not None:
            data["sim_trace"] = self.sim_trace.to_json()
        return data


def _metric_dict(row: TrainingEpisode | EvaluationTrial) -> dict[str, Any]:
    data = dict(vars(row))  # flat rows: a copy of the fields, without asdict's deep copy
    # DeepRacer writes whole percentages and scores when they are whole: keep files diffable.
    for key in ("completion_percentage", "reward_score"):
        if key in data and float(data[key]).is_integer():
            data[key] = int(data[key])
    return data


def read_training_metrics(path: Path) -> TrainingMetrics:
    return parse_training_metrics(_read_text(path, MAX_TRAINING_METRICS_BYTES), str(path))


def parse_training_metrics(text: str, where: str) -> TrainingMetrics:
    data = parse_json_object(text, where)
    rows = _metric_rows(data, where)
    episodes = tuple(_row(TrainingEpisode, row, where, i) for i, row in enumerate(rows))
    best = data.get("best_model_metric", "progress")
    version = data.get("version", 2.0)
    return TrainingMetrics(
        episodes,
        best if isinstance(best, str) else "progress",
        float(version) if isinstance(version, int | float) else 2.0,
        _sim_trace_sample(data.get("sim_trace")),
    )


def _sim_trace_sample(data: object) -> SimTraceSample | None:
    """Our own extra key: informative only, so a malformed one is dropped, never an error."""
    if not isinstance(data, Mapping):
        return None
    counts: list[int] = []
    for name in ("episodes", "traced_episodes", "traced_steps"):
        count = data.get(name)
        if not isinstance(count, int) or isinstance(count, bool) or count < 0:
            return None
        counts.append(count)
    rule = data.get("rule", "")
    episodes, traced_episodes, traced_steps = counts
    return SimTraceSample(
        episodes, traced_episodes, traced_steps, rule[:200] if isinstance(rule, str) else ""
    )


def write_training_metrics(path: Path, metrics: TrainingMetrics) -> None:
    write_text_atomic(path, training_metrics_text(metrics))


# One row per line between a fixed first line and a closing line: rows can then be added
# in place over the closing line (see `append_training_metrics`), and the file is still
# the single JSON object DeepRacer's tools read.
_METRICS_HEAD = '{"metrics":['
_METRICS_CLOSE = "\n]"


def training_metrics_text(metrics: TrainingMetrics) -> str:
    return _METRICS_HEAD + _metric_lines(metrics.episodes) + _metrics_tail(metrics)


def _metric_lines(rows: Sequence[TrainingEpisode]) -> str:
    return ",".join("\n" + json.dumps(_metric_dict(row), separators=(",", ":")) for row in rows)


def _metrics_tail(metrics: TrainingMetrics) -> str:
    data = metrics.to_json()
    del data["metrics"]
    return _METRICS_CLOSE + "," + json.dumps(data, separators=(",", ":"))[1:] + "\n"


def append_training_metrics(
    path: Path, rows: Sequence[TrainingEpisode], template: TrainingMetrics
) -> None:
    """Add `rows` to the TrainingMetrics file at `path` (made if missing).

    The new rows and the closing line are written over the old closing line in one write,
    so the cost grows with the new rows, not with the whole log (which holds every episode
    of every car), and a killed process leaves the old file or the new one. `template` gives
    the closing keys (version, best-model metric, sim-trace counts); its episodes are
    ignored. A file written elsewhere is rewritten once, atomically, in this layout.
    """
    tail = _metrics_tail(template)
    lines = _metric_lines(rows)
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        write_text_atomic(path, _METRICS_HEAD + lines + tail)
        return
    keep, empty = _rows_end(path, size)
    if keep is None:
        old = read_training_metrics(path)
        merged = replace(template, episodes=old.episodes + tuple(rows))
        write_text_atomic(path, training_metrics_text(merged))
        return
    joiner = "" if empty or not lines else ","
    data = (joiner + lines + tail).encode("utf-8")
    # JSON allows trailing spaces: a shorter closing line never leaves old bytes behind.
    data = data[:-1] + b" " * max(0, size - keep - len(data)) + b"\n"
    fd = os.open(path, os.O_WRONLY)
    try:
        if os.pwrite(fd, data, keep) != len(data):
            raise DeepRacerFileError(f"{path}: the disk is full; free some space.")
    finally:
        os.close(fd)


def _rows_end(path: Path, size: int) -> tuple[int | None, bool]:
    """Where the rows of a file in our line layout end, and whether there are none."""
    head = _METRICS_HEAD.encode("utf-8")
    with path.open("rb") as handle:
        if handle.read(len(head)) != head:
            return None, False
        start = max(len(head), size - 65_536)  # the closing line is short; rows are < 1 kB
        handle.seek(start)
        chunk = handle.read()
    close = chunk.rfind(_METRICS_CLOSE.encode("utf-8"))
    if close < 0:
        return None, False
    end = start + close
    return end, end == len(head)


def training_metrics_rows_after(
    path: Path, offset: int
) -> tuple[tuple[TrainingEpisode, ...], int | None]:
    """The rows of the TrainingMetrics file at `path` from byte `offset` on, and the offset
    to read from next time, so a watcher of a training reads each row once however long
    the log grows: in our line layout a written row never moves (appends go over the
    closing line). A file in another layout is read whole when `offset` is 0, and the next
    offset is None: it has no place to continue from. A missing file has no rows yet.
    Rows still being written are left for the next call."""
    try:
        size = path.stat().st_size
        end, empty = _rows_end(path, size)
        if end is None:
            if offset:
                return (), None
            return read_training_metrics(path).episodes, None
        start = max(offset, len(_METRICS_HEAD))
        if empty or end <= start:
            return (), max(offset, 0)
        with path.open("rb") as handle:
            handle.seek(start)
            chunk = handle.read(end - start)
    except FileNotFoundError:
        return (), 0
    except OSError as error:
        raise DeepRacerFileError(f"{path}: cannot read it ({error.strerror}).") from None
    rows: list[TrainingEpisode] = []
    done = start
    for line in chunk.split(b"\n"):
        text = line.strip().strip(b",")
        if text:
            try:
                data = json.loads(text)
                rows.append(_row(TrainingEpisode, data, path, len(rows)))
            except (json.JSONDecodeError, UnicodeDecodeError, DeepRacerFileError):
                break  # caught mid-write: this row and the rest come next time
        done += len(line) + 1
    return tuple(rows), min(done, end)


def training_metrics_end(path: Path) -> tuple[TrainingEpisode | None, SimTraceSample | None]:
    """The last row of a TrainingMetrics file and its sim-trace counts, reading only the
    file's end when it is in our line layout (a resumed training needs just these from a
    log of every episode). (None, None) when there is no file."""
    try:
        size = path.stat().st_size
        end, empty = _rows_end(path, size)
        if end is None:
            metrics = read_training_metrics(path)
            return (metrics.episodes[-1] if metrics.episodes else None), metrics.sim_trace
        with path.open("rb") as handle:
            start = max(0, end - 65_536)
            handle.seek(start)
            chunk = handle.read(size - start)
    except FileNotFoundError:
        return None, None
    except OSError as error:
        raise DeepRacerFileError(f"{path}: cannot read it ({error.strerror}).") from None
    rows, close = chunk[: end - start], chunk[end - start + len(_METRICS_CLOSE) + 1 :]
    try:
        closing = json.loads(b"{" + close)
    except (json.JSONDecodeError, UnicodeDecodeError):
        closing = {}
    sample = _sim_trace_sample(closing.get("sim_trace") if isinstance(closing, dict) else None)
    if empty:
        return None, sample
    line = rows[rows.rfind(b"\n") + 1 :].decode("utf-8", errors="replace")
    return _row(TrainingEpisode, parse_json_object(line, str(path)), path, 0), sample


def read_evaluation_metrics(path: Path) -> tuple[EvaluationTrial, ...]:
    return parse_evaluation_metrics(_read_text(path, MAX_METRICS_BYTES), str(path))


def parse_evaluation_metrics(text: str, where: str) -> tuple[EvaluationTrial, ...]:
    rows = _metric_rows(parse_json_object(text, where), where)
    return tuple(_row(EvaluationTrial, row, where, i) for i, row in enumerate(rows))


def write_evaluation_metrics(
    path: Path, trials: Sequence[EvaluationTrial], physics: str | None = None
) -> None:
    write_text_atomic(path, evaluation_metrics_text(trials, physics))


def evaluation_metrics_text(trials: Sequence[EvaluationTrial], physics: str | None = None) -> str:
    """DeepRacer's EvaluationMetrics; with `physics`, racer-tui's own top-level key saying
    which simulator timed the laps (sim.physics.labels; DeepRacer's readers ignore it)."""
    document: dict[str, Any] = {"metrics": [_metric_dict(t) for t in trials]}
    if physics is not None:
        document["physics"] = physics
    return json.dumps(document) + "\n"


def read_evaluation_physics(path: Path) -> str | None:
    """The `physics` an evaluation file names (see evaluation_metrics_text), or None when it
    names none (DeepRacer's own files, and racer-tui's before physics was recorded)."""
    return parse_evaluation_physics(_read_text(path, MAX_METRICS_BYTES), str(path))


def parse_evaluation_physics(text: str, where: str) -> str | None:
    physics = parse_json_object(text, where).get("physics")
    if physics is None:
        return None
    if not is_physics(physics):
        raise DeepRacerFileError(
            f"{where}: physics {physics!r} is not 'racer-tui/<version>' or 'deepracer'."
        )
    return str(physics)


def evaluation_stamp(when: datetime | None = None) -> str:
    """`YYYYmmddHHMMSS`: DRfC names an evaluation by it, and the names sort by time."""
    return (when or datetime.now(UTC)).strftime("%Y%m%d%H%M%S")


def evaluation_metrics_path(stamp: str) -> str:
    """Where a DRfC model folder keeps the evaluation's EvaluationMetrics."""
    return f"metrics/EvaluationMetrics-{stamp}.json"


def evaluation_trace_path(stamp: str) -> str:
    """Where a DRfC model folder keeps the evaluation's sim-trace (deepracer-utils reads
    exactly 14 digits here)."""
    return f"evaluation-{stamp}/evaluation-simtrace/0-iteration.csv"


def training_trace_path(iteration: int) -> str:
    """DRfC's training sim-trace of one iteration, numbered from 0."""
    return f"{TRAINING_SIMTRACE_DIR}/{iteration}-iteration.csv"


def stamp_in(name: str) -> str | None:
    """The 14-digit evaluation timestamp in a file or folder name (DRfC's digits, or
    DeepRacer on AWS's ISO time to the second), if there is one."""
    iso = _ISO_TIME.search(name)
    if iso is not None:
        with contextlib.suppress(ValueError):  # a date no calendar has is no stamp
            year, month, day, hour, minute, second = (int(part) for part in iso.groups())
            datetime(year, month, day, hour, minute, second, tzinfo=UTC)
            return "".join(iso.groups())
    match = _TIMESTAMP.search(name)
    return match.group(1) if match else None


def _metric_rows(data: Mapping[str, Any], path: Path | str) -> list[Any]:
    rows = data.get("metrics")
    if not isinstance(rows, list):
        raise DeepRacerFileError(f"{path}: expected a 'metrics' list as DeepRacer writes it.")
    return rows


_NUMBER_TYPES = (int, float)
RowT = TypeVar("RowT", TrainingEpisode, EvaluationTrial)


def _row(cls: type[RowT], row: object, path: Path | str, index: int) -> RowT:
    where = f"{path}: metrics row {index + 1}"
    if not isinstance(row, Mapping):
        raise DeepRacerFileError(f"{where} is not an object.")
    values: dict[str, Any] = {}
    for spec in fields(cls):
        if spec.name not in row:
            if spec.default is not MISSING:  # has a default: an optional key
                continue
            raise DeepRacerFileError(f"{where} has no {spec.name!r}.")
        value = row[spec.name]
        if spec.type == "str":
            if not isinstance(value, str) or len(value) > 64:
                raise DeepRacerFileError(f"{where}: {spec.name} must be a short text.")
        elif spec.type == "int":
            if (
                isinstance(value, bool)
                or not isinstance(value, _NUMBER_TYPES)
                or not (math.isfinite(value) and float(value).is_integer())
            ):
                raise DeepRacerFileError(f"{where}: {spec.name} must be a whole number.")
            value = int(value)
        else:
            if (
                isinstance(value, bool)
                or not isinstance(value, _NUMBER_TYPES)
                or not (math.isfinite(value))
            ):
                raise DeepRacerFileError(f"{where}: {spec.name} must be a number.")
            value = float(value)
        values[spec.name] = value
    return cls(**values)


# --- sim-trace CSV ---------------------------------------------------------------------

SIM_TRACE_COLUMNS = (
    "episode",
    "steps",
    "X",
    "Y",
    "yaw",
    "steer",
    "throttle",
    "action",
    "reward",
    "done",
    "all_wheels_on_track",
    "progress",
    "closest_waypoint",
    "track_len",
    "tstamp",
    "episode_status",
    "pause_duration",
)
PREPARE_STATUS = "prepare"


def trace_status(status: EpisodeStatus | str) -> str:
    """Sim-trace spelling of a status: 'Lap complete' -> 'lap_complete'."""
    return str(status).strip().lower().replace(" ", "_")


@dataclass(frozen=True)
class SimTraceRow:
    episode: int
    steps: int
    x: float
    y: float
    yaw: float  # degrees
    steer: float  # degrees
    throttle: float  # m/s
    action: int  # index for discrete spaces, -1 for continuous
    reward: float
    done: bool
    all_wheels_on_track: bool
    progress: float
    closest_waypoint: int
    track_len: float
    tstamp: float  # seconds
    episode_status: str
    pause_duration: float = 0.0

    def cells(self) -> list[str]:
        return [
            str(self.episode),
            f"{float(self.steps):.1f}",
            repr(self.x),
            repr(self.y),
            repr(self.yaw),
            repr(self.steer),
            repr(self.throttle),
            str(self.action),
            repr(self.reward),
            str(self.done),
            str(self.all_wheels_on_track),
            repr(self.progress),
            str(self.closest_waypoint),
            repr(self.track_len),
            f"{self.tstamp:.3f}",
            self.episode_status,
            repr(self.pause_duration),
        ]


def sim_trace_text(rows: Iterable[SimTraceRow]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(SIM_TRACE_COLUMNS)
    for row in rows:
        writer.writerow(row.cells())
    return out.getvalue()


def write_sim_trace(path: Path, rows: Iterable[SimTraceRow]) -> None:
    write_text_atomic(path, sim_trace_text(rows))


@dataclass(frozen=True)
class SimTraceColumns:
    """Many sim-trace rows as numpy columns (one entry per row; `track_len` is one value):
    how training and evaluation write thousands of rows without a Python object per row."""

    episode: NDArray[np.int64]
    steps: NDArray[np.int64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    yaw: NDArray[np.float64]
    steer: NDArray[np.float64]
    throttle: NDArray[np.float64]
    action: NDArray[np.int64]
    reward: NDArray[np.float64]
    done: NDArray[np.bool_]
    all_wheels_on_track: NDArray[np.bool_]
    progress: NDArray[np.float64]
    closest_waypoint: NDArray[np.int64]
    track_len: float
    tstamp: NDArray[np.float64]
    episode_status: Sequence[str]
    pause_duration: NDArray[np.float64] | None = None  # None: no car was ever held

    def __len__(self) -> int:
        return len(self.steps)


# One row of SimTraceColumns: four decimals for positions, angles and scores (a tenth of a
# millimetre), milliseconds for the clock; steps as simapp writes them ("12.0").
_ROW_FORMAT = "%d,%d.0,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%.4f,%s,%s,%.4f,%d,%s,%.3f,%s,%.3f\n"


def sim_trace_lines(columns: SimTraceColumns) -> str:
    """CSV rows (no header), each ending in a newline, in SIM_TRACE_COLUMNS order."""
    n = len(columns)
    if n == 0:
        return ""

    def flag(values: NDArray[Any]) -> list[str]:
        return np.where(np.asarray(values, dtype=bool), "True", "False").tolist()  # type: ignore[no-any-return]

    pause = np.zeros(n) if columns.pause_duration is None else columns.pause_duration
    cells = zip(
        np.asarray(columns.episode, dtype=np.int64).tolist(),
        np.asarray(columns.steps, dtype=np.int64).tolist(),
        np.asarray(columns.x, dtype=np.float64).tolist(),
        np.asarray(columns.y, dtype=np.float64).tolist(),
        np.asarray(columns.yaw, dtype=np.float64).tolist(),
        np.asarray(columns.steer, dtype=np.float64).tolist(),
        np.asarray(columns.throttle, dtype=np.float64).tolist(),
        np.asarray(columns.action, dtype=np.int64).tolist(),
        np.asarray(columns.reward, dtype=np.float64).tolist(),
        flag(columns.done),
        flag(columns.all_wheels_on_track),
        np.asarray(columns.progress, dtype=np.float64).tolist(),
        np.asarray(columns.closest_waypoint, dtype=np.int64).tolist(),
        [repr(float(columns.track_len))] * n,
        np.asarray(columns.tstamp, dtype=np.float64).tolist(),
        list(columns.episode_status),
        np.asarray(pause, dtype=np.float64).tolist(),
        strict=True,
    )
    # %-formatting row by row is C code: about 3 microseconds a row.
    return "".join([_ROW_FORMAT % row for row in cells])


def append_sim_trace(path: Path, lines: str) -> None:
    """Add rows to a sim-trace CSV (with its header when the file is new) in one write.

    Appending keeps a long training's trace cheap; a killed process can at worst leave a
    last line cut short, which `sim.training` trims when the next run starts.
    """
    if not lines:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a", encoding="utf-8", newline="") as handle:
        if handle.tell() == 0:
            lines = ",".join(SIM_TRACE_COLUMNS) + "\n" + lines
        handle.write(lines)


def read_sim_trace(path: Path) -> list[SimTraceRow]:
    text = _read_text(path, MAX_METRICS_BYTES)
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    if header is None or tuple(header[: len(SIM_TRACE_COLUMNS)]) != SIM_TRACE_COLUMNS:
        raise DeepRacerFileError(f"{path}: not a DeepRacer sim-trace CSV (unexpected header).")
    rows: list[SimTraceRow] = []
    for line, cells in enumerate(reader, start=2):
        try:
            rows.append(_trace_row(cells))
        except (ValueError, IndexError):
            raise DeepRacerFileError(f"{path}: line {line} is not a valid sim-trace row.") from None
    return rows


def last_sim_trace_row(path: Path) -> SimTraceRow | None:
    """The last row of a sim-trace CSV, reading only the file's end (a training's trace
    can be megabytes; a live view needs the newest step)."""
    try:
        with path.open("rb") as handle:
            header = handle.readline(4096).decode("utf-8", errors="replace").strip()
            size = handle.seek(0, io.SEEK_END)
            handle.seek(max(0, size - 4096))
            tail = handle.read().decode("utf-8", errors="replace")
    except OSError as error:
        raise DeepRacerFileError(f"{path}: cannot read it ({error.strerror}).") from None
    if tuple(header.split(",")[: len(SIM_TRACE_COLUMNS)]) != SIM_TRACE_COLUMNS:
        raise DeepRacerFileError(f"{path}: not a DeepRacer sim-trace CSV (unexpected header).")
    lines = [line for line in tail.split("\n") if line.strip()]
    if not lines or lines[-1].startswith("episode,"):
        return None
    try:
        return _trace_row(next(csv.reader([lines[-1]])))
    except (ValueError, IndexError):
        raise DeepRacerFileError(f"{path}: its last line is not a valid sim-trace row.") from None


def _trace_action(text: str) -> int:
    """The action index of a discrete space; a continuous space's row holds its action as
    "[steering speed]" (simapp writes the pair), which is -1 here as racer-tui writes it."""
    if text.startswith("[") and text.endswith("]"):
        for value in text[1:-1].split():
            float(value)  # a malformed pair is a bad row (ValueError)
        return -1
    number = float(text)
    if not math.isfinite(number):
        raise ValueError(text)
    return int(number)


def _trace_row(cells: list[str]) -> SimTraceRow:
    def flag(text: str) -> bool:
        if text not in ("True", "False"):
            raise ValueError(text)
        return text == "True"

    def number(text: str) -> float:
        value = float(text)
        if not math.isfinite(value):
            raise ValueError(text)
        return value

    return SimTraceRow(
        episode=int(cells[0]),
        steps=int(number(cells[1])),
        x=number(cells[2]),
        y=number(cells[3]),
        yaw=number(cells[4]),
        steer=number(cells[5]),
        throttle=number(cells[6]),
        action=_trace_action(cells[7]),
        reward=number(cells[8]),
        done=flag(cells[9]),
        all_wheels_on_track=flag(cells[10]),
        progress=number(cells[11]),
        closest_waypoint=int(number(cells[12])),
        track_len=number(cells[13]),
        tstamp=number(cells[14]),
        episode_status=cells[15][:32],
        pause_duration=number(cells[16]) if len(cells) > 16 else 0.0,
    )


# --- finding the files in folders people download ----------------------------------------


@dataclass(frozen=True)
class DeepRacerFiles:
    """Where the DeepRacer files are in a folder, whichever tool wrote it."""

    root: Path
    model_metadata: Path | None = None
    hyperparameters: Path | None = None
    training_params: Path | None = None
    reward_function: Path | None = None
    training_metrics: tuple[Path, ...] = ()
    evaluation_metrics: tuple[Path, ...] = ()  # oldest first
    sim_traces: tuple[Path, ...] = ()  # every sim-trace CSV, training and evaluation
    training_traces: tuple[Path, ...] = ()  # `<N>-iteration.csv` files, by N
    # (stamp, file): an evaluation's sim-trace and the 14-digit stamp its folder names, or
    # None where the download kept no stamp (the console flattens a single evaluation).
    evaluation_traces: tuple[tuple[str | None, Path], ...] = ()

    @property
    def latest_evaluation(self) -> Path | None:
        return self.evaluation_metrics[-1] if self.evaluation_metrics else None


_TIMESTAMP = re.compile(r"(\d{14})")
# DeepRacer on AWS names a job's files by JavaScript's toISOString(), in UTC:
# `2026-07-24T15:06:12.345Z-deepracerindy-evaluation-<id>.json`.
_ISO_TIME = re.compile(r"(\d{4})-(\d{2})-(\d{2})T(\d{2}):(\d{2}):(\d{2})(?:\.\d{1,9})?Z")


def _by_timestamp(paths: Iterable[Path]) -> tuple[Path, ...]:
    def key(path: Path) -> tuple[str, str]:
        return (stamp_in(path.name) or "", path.name)

    return tuple(sorted(paths, key=key))


def locate_files(root: Path) -> DeepRacerFiles:
    """Find DeepRacer files in a DeepRacer-for-Cloud model folder (`model/`, `ip/`,
    `metrics/`, `training-simtrace/`, `evaluation-<stamp>/`; racer-tui's model folders are
    these), an AWS console log download (`metrics/training/`, `metrics/evaluation/`,
    `sim-trace/`) or a racer-tui folder of the old flat layout. Symlinks are not followed
    out of `root`."""
    root = Path(root)

    def first(*candidates: str) -> Path | None:
        for candidate in candidates:
            path = root / candidate
            if path.is_file() and not path.is_symlink():
                return path
        return None

    def every(*patterns: str) -> list[Path]:
        found: list[Path] = []
        for pattern in patterns:
            found.extend(
                p
                for p in root.glob(pattern)
                if p.is_file() and not any(part.is_symlink() for part in _parts(root, p))
            )
        return found

    training_traces = every(
        TRAINING_SIMTRACE_GLOB,
        f"{LEGACY_SIM_TRACE_DIR}/training/training-simtrace/*-iteration.csv",
        f"{LEGACY_SIM_TRACE_DIR}/training/*/training-simtrace/*-iteration.csv",
    )
    evaluation_traces = [
        (stamp_in(path.parent.parent.name), path)
        for path in every(
            EVALUATION_SIMTRACE_GLOB,
            f"{LEGACY_SIM_TRACE_DIR}/evaluation/*/evaluation-simtrace/*-iteration.csv",
        )
    ]
    evaluation_traces += [
        (None, path) for path in every(f"{LEGACY_SIM_TRACE_DIR}/evaluation/*-iteration.csv")
    ]
    return DeepRacerFiles(
        root=root,
        model_metadata=first(MODEL_METADATA_PATH, MODEL_METADATA),
        hyperparameters=first(HYPERPARAMETERS_PATH, HYPERPARAMETERS),
        training_params=first(TRAINING_PARAMS, f"ip/{TRAINING_PARAMS}"),
        reward_function=first(REWARD_FUNCTION, f"model/{REWARD_FUNCTION}"),
        training_metrics=_by_timestamp(
            every(
                LEGACY_TRAINING_METRICS, "metrics/TrainingMetrics*.json", "metrics/training/*.json"
            )
        ),
        evaluation_metrics=_by_timestamp(
            every(
                LEGACY_EVALUATION_GLOB,
                "metrics/EvaluationMetrics*.json",
                "metrics/evaluation/*.json",
                # DeepRacer on AWS's leaderboard submissions: evaluations, as DRoA writes them
                "metrics/submission/*.json",
            )
        ),
        sim_traces=tuple(sorted({*training_traces, *(path for _, path in evaluation_traces)})),
        training_traces=tuple(sorted(training_traces, key=_iteration_number)),
        evaluation_traces=tuple(
            sorted(evaluation_traces, key=lambda pair: (pair[0] or "", pair[1]))
        ),
    )


def _parts(root: Path, path: Path) -> list[Path]:
    """`path` and each folder between it and `root`: none may be a symlink."""
    chain = [path]
    for parent in path.parents:
        if parent == root:
            break
        chain.append(parent)
    return chain


def _iteration_number(path: Path) -> tuple[int, str]:
    number = path.name.split("-", 1)[0]
    return (int(number) if number.isdigit() else -1, str(path))


# --- reading safely ----------------------------------------------------------------------


def _read_text(path: Path, limit: int) -> str:
    try:
        size = path.stat().st_size
        if size > limit:
            raise DeepRacerFileError(
                f"{path}: the file is {size:,} bytes, more than the {limit:,} allowed."
            )
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DeepRacerFileError(f"{path}: the file does not exist.") from None
    except UnicodeDecodeError:
        raise DeepRacerFileError(f"{path}: not a UTF-8 text file.") from None
    except OSError as error:
        raise DeepRacerFileError(f"{path}: cannot read it ({error.strerror}).") from None


def parse_json_object(text: str, where: str) -> dict[str, Any]:
    """A JSON object from untrusted text; `where` (a file or member name) leads every error."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise DeepRacerFileError(
            f"{where}: not valid JSON (line {error.lineno}, column {error.colno}); fix the syntax."
        ) from None
    except RecursionError:
        raise DeepRacerFileError(
            f"{where}: JSON nested too deeply to be a DeepRacer file."
        ) from None
    if not isinstance(data, dict):
        raise DeepRacerFileError(f"{where}: expected a JSON object at the top level.")
    return data

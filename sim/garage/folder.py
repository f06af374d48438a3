"""Model folders: the garage, where each of a racer's models is one folder of DeepRacer files.

A model is `data_home()/models/NAME` laid out as a deepracer-for-cloud model folder, so
deepracer-utils' `DeepRacerLog(folder)` reads it unchanged:

    model/model_metadata.json        ip/hyperparameters.json
    reward_function.py               training_params.yaml
    metrics/TrainingMetrics.json     metrics/EvaluationMetrics-<stamp>.json
    training-simtrace/<N>-iteration.csv
    evaluation-<stamp>/evaluation-simtrace/0-iteration.csv

with racer-tui's own files beside them: the trainer's `policy.safetensors`,
`checkpoints/`, `training-state.json` and the `.training.lock` a training holds. Formats
and DeepRacer's names are in `sim.deepracer.files`; this module knows the folder and what
state the model is in.
Folders of racer-tui's older flat layout are moved into this one when first opened
(`sim.garage.migrate`).

Folders are created whole: everything is written into a hidden temporary folder beside
the final one, which is then renamed into place, so a crash never leaves half a model.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import psutil

from sim.deepracer.car_look import CarLook
from sim.deepracer.files import (
    EVALUATION_METRICS_GLOB,
    HYPERPARAMETERS_PATH,
    MODEL_METADATA,
    MODEL_METADATA_PATH,
    REWARD_FUNCTION,
    TRAINING_METRICS_PATH,
    TRAINING_PARAMS,
    TRAINING_SIMTRACE_DIR,
    DeepRacerFileError,
    EvaluationTrial,
    ModelMetadata,
    TrainingMetrics,
    TrainingParams,
    check_hyperparameters,
    evaluation_metrics_path,
    evaluation_trace_path,
    read_evaluation_metrics,
    read_hyperparameters,
    read_model_metadata,
    read_training_metrics,
    read_training_params,
    stamp_in,
    write_hyperparameters,
    write_model_metadata,
    write_training_params,
)
from sim.deepracer.vocabulary import is_physics
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.home import data_home
from sim.foundation.ids import canonical_json
from sim.foundation.names import NAME_RULE, is_valid_name
from sim.foundation.remedies import Fix, RemedyError, echoed
from sim.garage.migrate import MigrationError, migrate_folder, needs_migration
from sim.physics.labels import BEFORE_VERSIONING, DEEPRACER
from sim.reward.function import check_reward_code, load_reward_function
from sim.sensors.randomisation.settings import CameraRandomisation, read_camera_randomisation
from sim.tracks.catalog import list_tracks, resolve_track
from sim.tracks.track import Track, TrackError

if TYPE_CHECKING:
    from sim.reward.function import RewardFunction

MODELS_DIR = "models"
TRAINING_SUMMARY_FILE = "training-summary.json"  # a bundle's training, kept when installed
POLICY_FILE = "policy.safetensors"
# An imported DeepRacer car archive, kept whole (sim.car_export reads it).
CAR_ARCHIVE_FILE = "car-model.tar.gz"
CHECKPOINTS_DIR = "checkpoints"
TRAINING_STATE_FILE = "training-state.json"
TRAINING_LOCK_FILE = ".training.lock"
TRAINING_LOG_FILE = "training-log.jsonl"
TRAINING_HISTORY_FILE = "training-history.jsonl"
TRAINING_STATES = ("running", "stopped", "finished", "failed")
# How a training computes a policy (sim.training.ppo.training_numerics), recorded on the
# model as the physics it learnt is.
FLOAT32 = "float32"
BF16_CONVOLUTIONS = "bfloat16 convolutions"
TRAINING_NUMERICS = (FLOAT32, BF16_CONVOLUTIONS)
MAX_REWARD_BYTES = 1_000_000
MAX_TRAINING_STATE_BYTES = 64_000
MAX_MINUTES = 100_000.0  # training_params.yaml's MAX_MINUTES limit
# A model's time limit is at least a minute (less learns nothing); a single training run
# from the command line may still be shorter, for scripts and tests.
MIN_MINUTES = 1.0


def models_dir() -> Path:
    """Where the garage keeps model folders (created on first use)."""
    path = data_home() / MODELS_DIR
    path.mkdir(parents=True, exist_ok=True)
    return path


class ModelError(RemedyError):
    """A model that is missing, misnamed or unusable; one sentence saying what to do."""


class ModelStatus(StrEnum):
    UNTRAINED = "untrained"
    TRAINING = "training"
    TRAINED = "trained"
    EVALUATED = "evaluated"


@dataclass(frozen=True)
class ModelFolder:
    """One model's folder. Reading methods raise ModelError naming the broken file."""

    path: Path

    @property
    def name(self) -> str:
        return self.path.name

    # --- where things are ------------------------------------------------------------

    @property
    def metadata_file(self) -> Path:
        return self.path / MODEL_METADATA_PATH

    @property
    def reward_file(self) -> Path:
        return self.path / REWARD_FUNCTION

    @property
    def hyperparameters_file(self) -> Path:
        return self.path / HYPERPARAMETERS_PATH

    @property
    def training_params_file(self) -> Path:
        return self.path / TRAINING_PARAMS

    @property
    def training_metrics_file(self) -> Path:
        """DeepRacer's TrainingMetrics: one row per episode of every car that trained."""
        return self.path / TRAINING_METRICS_PATH

    @property
    def policy_file(self) -> Path:
        """The weights races use, written by the trainer (tensors only)."""
        return self.path / POLICY_FILE

    @property
    def car_archive_file(self) -> Path:
        """A DeepRacer car archive this model drives with instead of a racer-tui policy
        (`model import FILE.tar.gz`): TensorFlow weights, raced but never trained here."""
        return self.path / CAR_ARCHIVE_FILE

    @property
    def checkpoints_dir(self) -> Path:
        """The trainer's resumable state; owned by sim.training."""
        return self.path / CHECKPOINTS_DIR

    @property
    def metrics_dir(self) -> Path:
        return self.training_metrics_file.parent

    @property
    def training_trace_dir(self) -> Path:
        """`<N>-iteration.csv`: the sim-trace of training iteration N (see sim.training.logbook)."""
        return self.path / TRAINING_SIMTRACE_DIR

    def evaluation_metrics_file(self, stamp: str) -> Path:
        return self.path / evaluation_metrics_path(stamp)

    def evaluation_trace_file(self, stamp: str) -> Path:
        """The sim-trace of the evaluation whose metrics are EvaluationMetrics-<stamp>.json."""
        return self.path / evaluation_trace_path(stamp)

    @property
    def training_log(self) -> Path:
        """The latest training run's events, one JSON line each (`sim.training.events`), as
        the run goes: written by whoever started it (the app or `racer-tui train`), so the
        app can follow a run that any of them started."""
        return self.path / TRAINING_LOG_FILE

    @property
    def training_history(self) -> Path:
        """Every run's PPO updates and system readings, one event per line (see
        `sim.training.run_history`): the curves TrainingMetrics.json does not keep."""
        return self.path / TRAINING_HISTORY_FILE

    @property
    def training_lock_file(self) -> Path:
        """Locked (flock) by the process training this model, for as long as it lives."""
        return self.path / TRAINING_LOCK_FILE

    def training_locked(self) -> bool:
        """Whether a process holds the training lock now (the state file may lag behind:
        a training that has just started has the lock before it writes its state)."""

        try:
            with self.training_lock_file.open("a+b") as handle:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                fcntl.flock(handle, fcntl.LOCK_UN)
        except BlockingIOError:
            return True
        except OSError:
            return False
        return False

    @property
    def training_state_file(self) -> Path:
        """Written atomically by the trainer: {"state", "pid", "started_at", "updated_at",
        "elapsed_seconds", "steps", "episodes", "best_progress", "message", "problem", "fix",
        "physics", "budget_minutes"}: `problem` and `fix` are a failure's message without
        its remedy and the remedy's name (`sim.foundation.remedies.Fix`), or empty."""
        return self.path / TRAINING_STATE_FILE

    # --- the DeepRacer files -----------------------------------------------------------

    def metadata(self) -> ModelMetadata:
        return _checked(read_model_metadata, self.metadata_file)

    def hyperparameters(self) -> dict[str, float | int | str]:
        return _checked(read_hyperparameters, self.hyperparameters_file)

    def training_params(self) -> TrainingParams:
        return _checked(read_training_params, self.training_params_file)

    def reward_source(self) -> str:
        path = self.reward_file
        try:
            if path.stat().st_size > MAX_REWARD_BYTES:
                raise ModelError(f"{path}: the reward function is larger than 1 MB.")
            return path.read_bytes().decode("utf-8-sig")
        except FileNotFoundError:
            raise ModelError(
                f"{path}: the reward function is missing; copy one in or re-create the model."
            ) from None
        except UnicodeDecodeError:
            raise ModelError(f"{path}: not UTF-8 text; save it as UTF-8.") from None
        except OSError as error:
            raise ModelError(f"{path}: cannot read it ({error.strerror}).") from None

    def reward_function(self) -> RewardFunction:
        """The loaded reward function (RewardFunctionError names the file and line)."""

        self.reward_source()  # the same clear errors for a missing or huge file
        return load_reward_function(self.reward_file)

    def track(self) -> Track:
        """The track the model trains on (training_params.yaml's WORLD_NAME)."""

        world = self.training_params().world_name
        try:
            return resolve_track(world)
        except TrackError as error:
            where = f"model {self.name!r} trains on track {world!r}"
            raise ModelError(  # the app's remedy: choose the model's track (or import it)
                f"{where}: {error}",
                problem=f"{where}: {error.problem}",
                fix=Fix.CHOOSE_TRACK if error.fix is not None else None,
            ) from None

    # --- metrics -------------------------------------------------------------------------

    def training_metrics(self) -> TrainingMetrics | None:
        """The training metrics, or None before the first training run."""
        if not self.training_metrics_file.is_file():
            return None
        return _checked(read_training_metrics, self.training_metrics_file)

    def evaluation_files(self) -> list[Path]:
        """`metrics/EvaluationMetrics-*.json`, oldest first (the names carry a sortable
        timestamp)."""
        return sorted(
            path
            for path in self.path.glob(EVALUATION_METRICS_GLOB)
            if path.is_file() and not path.is_symlink()
        )

    def stale_evaluation(self, path: Path) -> str | None:
        """A sentence when the evaluation `path` was made before the model last trained
        (its laps are not the policy's any more), else None."""
        stamp = stamp_in(path.name)
        state = self.training_state()
        trained = None if state is None else state.get("updated_at")
        if stamp is None or not isinstance(trained, str):
            return None
        try:
            evaluated = datetime.strptime(stamp, "%Y%m%d%H%M%S").replace(tzinfo=UTC)
            last_trained = datetime.fromisoformat(trained)
        except ValueError:
            return None
        if last_trained.tzinfo is None or last_trained <= evaluated:
            return None
        return (
            f"{self.name}'s latest evaluation ({evaluated:%Y-%m-%d %H:%M} UTC) was made before "
            f"it last trained ({last_trained.astimezone(UTC):%Y-%m-%d %H:%M} UTC), so its laps "
            "are not the policy's any more"
        )

    def latest_evaluation(self) -> tuple[EvaluationTrial, ...] | None:
        files = self.evaluation_files()
        if not files:
            return None
        return _checked(read_evaluation_metrics, files[-1])

    def best_evaluation_lap(self) -> float | None:
        """The fastest completed lap over all evaluations, in seconds."""
        best: float | None = None
        for path in self.evaluation_files():
            for trial in _checked(read_evaluation_metrics, path):
                lap = trial.lap_time_seconds
                if lap is not None and (best is None or lap < best):
                    best = lap
        return best

    # --- state ---------------------------------------------------------------------------

    def has_policy(self) -> bool:
        """The model can drive: racer-tui's trained policy, or an imported car archive."""
        return self.policy_file.is_file() or self.has_car_archive()

    def has_car_archive(self) -> bool:
        return self.car_archive_file.is_file()

    def drives_with_car_archive(self) -> bool:
        """It races with a DeepRacer car archive's graph, having no racer-tui policy."""
        return self.has_car_archive() and not self.policy_file.is_file()

    def car_archive_problem(
        self, doing: str, instead: str = "create a new model to train your own"
    ) -> str | None:
        """One sentence when this model drives with a car archive, which racer-tui can race
        and export for the car but not `doing` (train, clone, bundle); None otherwise."""
        if not self.has_car_archive():
            return None
        return (
            f"model {self.name!r} drives with a DeepRacer car archive (TensorFlow weights), "
            f"which racer-tui races but cannot {doing}; {instead}."
        )

    def training_state(self) -> dict[str, Any] | None:
        """The trainer's last word on this model, or None if it never ran (or left junk)."""
        try:
            if self.training_state_file.stat().st_size > MAX_TRAINING_STATE_BYTES:
                return None
            data = json.loads(self.training_state_file.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            return None
        if not isinstance(data, dict) or data.get("state") not in TRAINING_STATES:
            return None
        return data

    def last_budget_minutes(self) -> float | None:
        """The time budget the last training run was given (the app offers it again)."""
        state = self.training_state()
        budget = None if state is None else state.get("budget_minutes")
        if isinstance(budget, int | float) and not isinstance(budget, bool) and budget > 0:
            return float(budget)
        return None

    def trained_physics(self) -> str | None:
        """The physics (sim.physics.labels) the policy learnt to drive, or None untrained. A
        policy whose trainer did not say was trained before physics was recorded."""

        if not self.has_policy():
            return None
        if self.drives_with_car_archive():
            return DEEPRACER  # DeepRacer's simulator trained its weights
        state = self.training_state()
        physics = None if state is None else state.get("physics")
        if physics is None:
            physics = self._kept_summary_value("physics")  # a model installed from a bundle
        return str(physics) if is_physics(physics) else BEFORE_VERSIONING

    def trained_numerics(self) -> str | None:
        """How its training computed the policy (one of `TRAINING_NUMERICS`: float32, or
        bfloat16 convolutions on a CPU with bfloat16 in hardware), or None when untrained,
        a car archive's, or trained before numerics were recorded."""
        if not self.has_policy() or self.drives_with_car_archive():
            return None
        state = self.training_state()
        numerics = None if state is None else state.get("numerics")
        if numerics is None:
            numerics = self._kept_summary_value("numerics")  # installed from a bundle
        return numerics if isinstance(numerics, str) and numerics in TRAINING_NUMERICS else None

    def _kept_summary_value(self, key: str) -> object:
        kept = self.path / TRAINING_SUMMARY_FILE
        try:
            if kept.stat().st_size > MAX_TRAINING_STATE_BYTES:
                return None
            data = json.loads(kept.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            return None
        return data.get(key) if isinstance(data, dict) else None

    def is_training(self) -> bool:
        """A trainer says it is running and its process is alive."""
        state = self.training_state()
        if state is None or state["state"] != "running":
            return False
        pid = state.get("pid")
        if isinstance(pid, bool) or not isinstance(pid, int) or pid <= 0:
            return False
        return bool(psutil.pid_exists(pid))

    def status(self) -> ModelStatus:
        if self.is_training():
            return ModelStatus.TRAINING
        if not self.has_policy():
            return ModelStatus.UNTRAINED
        files = self.evaluation_files()
        # Evaluated means its policy's laps are known: not when it trained since.
        if files and self.stale_evaluation(files[-1]) is None:
            return ModelStatus.EVALUATED
        return ModelStatus.TRAINED

    def content_hash(self) -> str:
        """Identifies the exact car: metadata plus policy weights (the same as its bundle's),
        or the car archive it drives with."""
        if self.policy_file.is_file():
            policy = self.policy_file.read_bytes()
        elif self.has_car_archive():
            policy = self.car_archive_file.read_bytes()
        else:
            policy = b""
        return model_content_hash(self.metadata(), policy)


def camera_randomisation_of(params: TrainingParams, where: str) -> CameraRandomisation:
    """The camera randomisation a model's training params ask for (off without keys); a bad
    key is a ModelError naming it (`where`: the params file)."""
    try:
        return read_camera_randomisation(params, where)
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None


def write_export(target: Path, data: bytes) -> None:
    """Write an exported file atomically; a place that cannot be written is one sentence."""
    try:
        write_bytes_atomic(target, data)
    except OSError as error:
        raise ModelError(
            f"cannot write {target} ({error.strerror or error}); choose another file name."
        ) from None


def export_target(out: Path, name: str) -> Path:
    """Where `-o OUT` puts model `name`'s export: inside OUT when it is a folder."""
    out = Path(out).expanduser()
    return out / name if out.is_dir() else out


def model_content_hash(metadata: ModelMetadata, policy_bytes: bytes) -> str:
    """SHA-256 over the canonical metadata JSON followed by the policy file's bytes."""
    digest = hashlib.sha256(canonical_json(metadata.to_json()))
    digest.update(policy_bytes)
    return digest.hexdigest()


_T = TypeVar("_T")


def _checked(reader: Callable[[Path], _T], path: Path) -> _T:
    try:
        return reader(path)
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None


# --- finding models ----------------------------------------------------------------------


def check_model_name(name: str) -> None:
    if not is_valid_name(name):
        raise ModelError(f"{echoed(name)} cannot be a model name; use {NAME_RULE}.")


def is_model_folder(path: Path) -> bool:
    """A model folder of the DRfC layout, or one of racer-tui's old layout to migrate."""
    return (path / MODEL_METADATA_PATH).is_file() or (
        path.is_dir() and (path / MODEL_METADATA).is_file()
    )


def is_racer_tui_folder(path: Path) -> bool:
    """A model folder racer-tui made: the old flat layout, or the DRfC layout with racer-tui's
    own files beside (a DRfC download has the same DeepRacer files, but none of these)."""
    if not is_model_folder(path):
        return False
    if (path / MODEL_METADATA).is_file():
        return True
    return any((path / own).exists() for own in (POLICY_FILE, TRAINING_STATE_FILE, CHECKPOINTS_DIR))


def open_model(name_or_path: str) -> ModelFolder:
    """A model in the garage by name, or the path of a model folder; a folder of racer-tui's
    old flat layout is moved into the DRfC layout on the way (see sim.garage.migrate)."""
    if is_valid_name(name_or_path):
        folder = models_dir() / name_or_path
        if is_model_folder(folder) or needs_migration(folder):
            return _opened(folder)
        if folder.is_dir():
            raise ModelError(
                f"{folder / MODEL_METADATA_PATH} does not exist, so the model folder is "
                "incomplete; copy the model in again, or delete the folder."
            )
    path = Path(name_or_path).expanduser()
    try:
        is_folder = path.is_dir()
    except OSError:  # no folder can have that name (too long, say): a name not found
        is_folder = False
    if is_folder and (is_model_folder(path) or needs_migration(path)):
        return _opened(path)
    if is_folder:
        problem = (
            f"{path / MODEL_METADATA_PATH} does not exist, so {name_or_path} is not a model folder"
        )
        raise ModelError(
            f"{problem}; give a garage model name, or bring in a DeepRacer download with "
            "`racer-tui model import PATH`.",
            problem=problem,
            fix=Fix.IMPORT_MODEL,
        )
    problem = f"there is no model named {echoed(name_or_path)}"
    raise ModelError(
        f"{problem}; `racer-tui model list` shows your models and `racer-tui model new NAME` "
        "creates one.",
        problem=problem,
        fix=Fix.CHOOSE_MODEL,
    )


def _opened(path: Path) -> ModelFolder:
    try:
        migrate_folder(path)
    except MigrationError as error:
        raise ModelError(str(error)) from None
    if not (path / MODEL_METADATA_PATH).is_file():
        # A folder cut short (by a crash or a copy) before its metadata was in place.
        raise ModelError(
            f"{path / MODEL_METADATA_PATH} does not exist, so the model folder is incomplete; "
            "copy the model in again or re-create it."
        )
    return ModelFolder(path)


def list_models() -> list[ModelFolder]:
    """The garage's models by name (hidden temporary folders are skipped). Folders of the
    old layout are migrated; one that cannot be still lists, and says why when opened."""
    found = model_folders()
    for folder in found:
        with contextlib.suppress(MigrationError):
            migrate_folder(folder.path)
    return found


def model_folders() -> list[ModelFolder]:
    """The garage's model folders by name, as they are (nothing migrated: a quick look)."""
    return [
        ModelFolder(path)
        for path in sorted(models_dir().iterdir(), key=lambda p: p.name.casefold())
        if is_valid_name(path.name) and is_model_folder(path)
    ]


def check_new_model_name(name: str) -> Path:
    """The folder a new model `name` will get; ModelError when the name is bad or taken."""
    check_model_name(name)
    # Compared without case: on macOS and Windows "Fast" and "fast" are one folder.
    folded = name.casefold()
    for existing in models_dir().iterdir():
        if existing.name.casefold() == folded and not existing.name.startswith("."):
            problem = f"a model named {existing.name!r} already exists"
            raise ModelError(
                f"{problem}; choose another name or delete it with "
                f"`racer-tui model delete {existing.name}`.",
                problem=problem,
                fix=Fix.RENAME,
            )
    return models_dir() / name


# --- creating models ---------------------------------------------------------------------


def create_model(
    name: str,
    *,
    track: str,
    metadata: ModelMetadata,
    hyperparameters: Mapping[str, object],
    reward_source: str,
    max_minutes: float = 60.0,
    populate: Callable[[ModelFolder], None] | None = None,
    notes: Mapping[str, str] | None = None,
    race_type: str = "TIME_TRIAL",
    race_keys: Mapping[str, object] | None = None,
    car_look: CarLook | None = None,
) -> ModelFolder:
    """Create model `name` in the garage, all at once (temporary folder, then rename).

    `track` is the name of a known track; `hyperparameters` are checked against DeepRacer's
    ranges over DeepRacer's defaults; `reward_source` must be Python defining
    `reward_function(params)` (checked without running it).
    `populate` may add more files (a policy, metrics) to the folder before it appears: it is
    called with the temporary folder. `notes` are kept in training_params.yaml (for
    example where the model came from). `race_type` and `race_keys` are DeepRacer's race
    type and its settings' keys (`sim.physics.objects.settings.race_keys`); `car_look` the
    car's shell and colour as DeepRacer wrote them (`sim.deepracer.car_look`).
    """

    final = check_new_model_name(name)
    try:
        checked = check_hyperparameters(hyperparameters, where="hyperparameters")
    except DeepRacerFileError as error:
        raise ModelError(str(error)) from None
    if not MIN_MINUTES <= max_minutes <= MAX_MINUTES:
        raise ModelError(
            f"the training time limit must be from {MIN_MINUTES:g} to {MAX_MINUTES:g} minutes, "
            f"not {max_minutes:g}."
        )
    resolved = _catalog_track(track)
    check_reward_code(reward_source, REWARD_FUNCTION)  # RewardFunctionError before writing
    params = TrainingParams(
        world_name=resolved.name,
        race_type=race_type,
        max_minutes=float(max_minutes),
        track_hash=resolved.content_hash,
        extra={
            **dict(race_keys or {}),
            **(car_look.to_params() if car_look is not None else {}),
            **dict(notes or {}),
        },
    )
    temporary = Path(tempfile.mkdtemp(prefix=f".{name}.", suffix=".tmp", dir=models_dir()))
    try:
        folder = ModelFolder(temporary)
        write_model_metadata(folder.metadata_file, metadata)
        write_hyperparameters(folder.hyperparameters_file, checked)
        write_training_params(folder.training_params_file, params)
        write_bytes_atomic(folder.reward_file, reward_source.encode("utf-8"))
        if populate is not None:
            populate(folder)
        os.chmod(temporary, 0o777 & ~_umask())  # mkdtemp makes 0700 folders
        # A second creator racing us: rename refuses a non-empty target, and we re-check.
        if final.exists():
            raise ModelError(f"a model named {name!r} was just created; choose another name.")
        os.rename(temporary, final)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise
    return ModelFolder(final)


def _catalog_track(track: str) -> Track:
    """A track the catalog knows by name: a model must find its track again later."""

    if track not in {info.name for info in list_tracks()} and Path(track).expanduser().is_file():
        raise ModelError(
            f"{track} is a track file, not a track name; import it first with "
            "`racer-tui tracks import FILE`, then give its name."
        )
    try:
        return resolve_track(track)
    except TrackError as error:
        raise ModelError(str(error), problem=error.problem, fix=error.fix) from None


def _umask() -> int:
    current = os.umask(0)
    os.umask(current)
    return current


def delete_model(folder: ModelFolder) -> None:
    """Remove a model folder; refuses while it trains. Renamed aside first, so a crash
    part-way leaves either the whole model or a hidden leftover, never half a model."""
    if folder.is_training():
        raise ModelError(
            f"model {folder.name!r} is training right now; stop the training first, then delete it."
        )
    graveyard = folder.path.with_name(f".{folder.name}.deleting")
    shutil.rmtree(graveyard, ignore_errors=True)
    os.rename(folder.path, graveyard)
    shutil.rmtree(graveyard)

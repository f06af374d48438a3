"""The submission assembler: one league submission from a model's DeepRacer files.

The seed project's five files are read through sim.deepracer.files (the one place that
knows their formats): model metadata, hyperparameters, training params, training metrics
and evaluation metrics (the latest, unless one is named). Three kinds of folder work:

- a racer-tui model folder (garage name or path): a DeepRacer-for-Cloud model folder with
  racer-tui's own files beside (an old flat one is migrated when opened);
- a DeepRacer-for-Cloud model folder: `model/`, `ip/`, `metrics/`;
- an AWS console log download: `metrics/training/`, `metrics/evaluation/`, `sim-trace/`.

The racer and the track are the two things a racer says; everything else comes from the
files. Evaluation metrics are required (they are what ranks); a racer-tui folder must
have its metadata, hyperparameters and training params, a DeepRacer-for-Cloud folder its
metadata; any other file is used when present. A file that is present but malformed is an
error naming it, and `assemble` touches no database: a failure writes nothing.
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from league.errors import LeagueError
from league.race_types import RACE_TYPES, TIME_TRIAL
from league.racers import check_name
from sim.deepracer.files import (
    HYPERPARAMETERS_PATH,
    MODEL_METADATA_PATH,
    TRAINING_PARAMS,
    DeepRacerFileError,
    DeepRacerFiles,
    EvaluationTrial,
    ModelMetadata,
    TrainingMetrics,
    TrainingParams,
    locate_files,
    read_evaluation_metrics,
    read_evaluation_physics,
    read_hyperparameters,
    read_model_metadata,
    read_training_metrics,
    read_training_params,
)
from sim.foundation.ids import canonical_json, content_hash
from sim.foundation.names import is_valid_name
from sim.foundation.remedies import Fix
from sim.garage.folder import (
    ModelError,
    ModelFolder,
    is_model_folder,
    is_racer_tui_folder,
    models_dir,
    open_model,
)
from sim.physics.labels import BEFORE_VERSIONING, DEEPRACER
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.tracks.catalog import resolve_track
from sim.tracks.droa import DroaDirectionError, droa_direction_sentence, training_world
from sim.tracks.track import Track, TrackError

RACER_TUI = "racer-tui"
DRFC = "deepracer-for-cloud"
CONSOLE = "console-logs"
MAX_TRIALS = 1000
# The columns of a stored submission lap (`submission_laps`), one per EvaluationLap field:
# what each lap of a submission record holds. Here, below the modules that store and sync
# submissions, so that league.records can read them without importing those.
LAP_COLUMNS = (
    "number",
    "time_seconds",
    "completion",
    "status",
    "offtracks",
    "crashes",
    "completed",
    "immobilized",
    "reversals",
)
# Counted since schema 15: NULL in the table and left out of a lap's record when none, so
# laps stored before keep their content hash (league.records).
OPTIONAL_LAP_COLUMNS = frozenset({"immobilized", "reversals"})


@dataclass(frozen=True)
class EvaluationLap:
    """One evaluation trial as the league keeps it (sim.race.rules.TimedLap for scoring)."""

    number: int
    time_seconds: float  # elapsed time, penalties included (DeepRacer counts them inside)
    completion: float
    status: str
    offtracks: int
    crashes: int
    completed: bool  # a full lap: only these have a lap time
    immobilized: int = 0
    reversals: int = 0

    @property
    def valid(self) -> bool:
        return self.completed

    @property
    def resets(self) -> int:
        """simapp's reset_count: every count that put the car back (or ended the trial)."""
        return self.offtracks + self.crashes + self.immobilized + self.reversals

    def record(self) -> dict[str, Any]:
        """The lap as its submission record holds it: the optional counts only when some."""
        row = asdict(self)
        row["completed"] = int(self.completed)
        for column in OPTIONAL_LAP_COLUMNS:
            if not row[column]:
                del row[column]
        return row

    @classmethod
    def from_trial(cls, number: int, trial: EvaluationTrial) -> EvaluationLap:
        return cls(
            number=number,
            time_seconds=trial.elapsed_time_in_milliseconds / 1000.0,
            completion=trial.completion_percentage,
            status=trial.episode_status,
            offtracks=trial.off_track_count,
            crashes=trial.crash_count,
            completed=trial.lap_time_seconds is not None,
            immobilized=trial.immobilized_count,
            reversals=trial.reversed_count,
        )


@dataclass(frozen=True)
class Submission:
    """Everything a submission row and its laps hold, before it is stored."""

    racer: str
    track_hash: str
    track_name: str
    model_name: str
    model_hash: str
    source: str  # RACER_TUI, DRFC or CONSOLE
    action_space: dict[str, Any] | None
    sensors: list[str] | None
    neural_network: str | None
    training_algorithm: str | None
    hyperparameters: dict[str, float | int | str] | None
    training: dict[str, Any] | None
    evaluation_file: str
    laps: tuple[EvaluationLap, ...]
    physics: str = CURRENT_PHYSICS  # which simulator timed the laps (sim.physics.labels)
    race_type: str = TIME_TRIAL  # league.race_types: which board its laps are ranked on
    stale: str | None = None  # why the evaluation is older than the policy, if it is

    @property
    def completed_laps(self) -> list[EvaluationLap]:
        return [lap for lap in self.laps if lap.completed]

    @property
    def best_lap(self) -> float | None:
        times = [lap.time_seconds for lap in self.completed_laps]
        return min(times) if times else None

    @property
    def fingerprint(self) -> str:
        """Same racer, track, car and laps: the same submission, however often it is sent."""
        return content_hash(
            {
                "racer": self.racer.casefold(),
                "track_hash": self.track_hash,
                "model_hash": self.model_hash,
                # The laps' fields from before their resets were kept: a file sent again
                # since is still known as the same submission.
                "laps": [
                    {
                        key: value
                        for key, value in vars(lap).items()
                        if key not in OPTIONAL_LAP_COLUMNS
                    }
                    for lap in self.laps
                ],
            }
        )


def assemble(
    model: str,
    racer: str,
    *,
    track: str | None = None,
    evaluation: Path | None = None,
) -> Submission:
    """Read a model's files into a Submission; LeagueError names any missing/bad file."""
    racer_name = check_name(racer)
    folder, garage_name = _model_folder(model)
    files = locate_files(folder)
    source = _layout(files, folder, garage_name)
    try:
        metadata = _optional(read_model_metadata, files.model_metadata)
        hyperparameters = _optional(read_hyperparameters, files.hyperparameters)
        params = _optional(read_training_params, files.training_params)
        training = _optional(
            read_training_metrics, files.training_metrics[-1] if files.training_metrics else None
        )
        evaluation_path = _evaluation_path(folder, files, evaluation)
        trials = read_evaluation_metrics(evaluation_path)
        physics = (
            (read_evaluation_physics(evaluation_path) or BEFORE_VERSIONING)
            if source == RACER_TUI
            else DEEPRACER
        )
    except DeepRacerFileError as error:
        raise LeagueError(str(error)) from None
    _require(source, folder, files)
    if not trials:
        raise LeagueError(f"{evaluation_path}: the evaluation has no trials; evaluate again.")
    if len(trials) > MAX_TRIALS:
        raise LeagueError(
            f"{evaluation_path}: {len(trials)} trials is more than the {MAX_TRIALS} allowed."
        )
    raced_on = _track(track, params, files, folder)
    return Submission(
        racer=racer_name,
        track_hash=raced_on.content_hash,
        track_name=raced_on.name,
        model_name=garage_name or folder.resolve().name,
        model_hash=_model_hash(
            folder,
            source=source,
            metadata=metadata,
            hyperparameters=hyperparameters,
            training=training,
            trials=trials,
        ),
        source=source,
        action_space=None if metadata is None else _action_summary(metadata),
        sensors=None if metadata is None else list(metadata.sensors),
        neural_network=None if metadata is None else metadata.neural_network,
        training_algorithm=None if metadata is None else metadata.training_algorithm,
        hyperparameters=hyperparameters,
        training=_training_summary(training, params, folder if source == RACER_TUI else None),
        evaluation_file=evaluation_path.name,
        laps=tuple(EvaluationLap.from_trial(i + 1, trial) for i, trial in enumerate(trials)),
        physics=physics,
        race_type=_race_type(params, files),
        stale=ModelFolder(folder).stale_evaluation(evaluation_path)
        if source == RACER_TUI
        else None,
    )


def _model_folder(model: str) -> tuple[Path, str | None]:
    """The folder to read, and the garage name when `model` named a garage model."""

    path = Path(model).expanduser()
    try:
        if is_valid_name(model) and is_model_folder(models_dir() / model):
            return open_model(model).path, model
        if path.is_dir() and is_racer_tui_folder(path):
            return open_model(str(path)).path, None  # an old flat folder moves on open
    except ModelError as error:
        raise LeagueError(str(error)) from None
    if path.is_dir():
        return path, None
    raise LeagueError(
        f"there is no model named {model!r} in the garage and no folder {model}; give a "
        "garage model name or the path of a model folder or DeepRacer log download."
    )


def _layout(files: DeepRacerFiles, folder: Path, garage_name: str | None) -> str:

    if garage_name is not None or is_racer_tui_folder(folder):
        return RACER_TUI
    metric_dirs = {
        path.relative_to(files.root).parts[1]
        for path in (*files.training_metrics, *files.evaluation_metrics)
        if len(path.relative_to(files.root).parts) > 2
    }
    # The console's log download, or DeepRacer on AWS's leaderboard submissions alone.
    if metric_dirs & {"training", "evaluation", "submission"} and files.model_metadata is None:
        return CONSOLE
    return DRFC


def _require(source: str, folder: Path, files: DeepRacerFiles) -> None:
    needed: dict[str, Path | None]
    if source == RACER_TUI:
        needed = {
            HYPERPARAMETERS_PATH: files.hyperparameters,
            TRAINING_PARAMS: files.training_params,
        }
    elif source == DRFC:
        needed = {MODEL_METADATA_PATH: files.model_metadata}
    else:
        needed = {}
    for name, path in needed.items():
        if path is None:
            raise LeagueError(
                f"{folder / name}: the file does not exist; a {source} model folder needs it."
            )


def _optional(reader: Any, path: Path | None) -> Any:
    return None if path is None else reader(path)


def _evaluation_path(folder: Path, files: DeepRacerFiles, named: Path | None) -> Path:
    if named is not None:
        path = Path(named).expanduser()
        if not path.is_absolute() and not path.exists() and (folder / path).exists():
            path = folder / path
        return path
    latest = files.latest_evaluation
    if latest is None:
        problem = f"{folder}: there are no evaluation metrics (metrics/EvaluationMetrics-*.json)"
        raise LeagueError(
            f"{problem}; evaluate the model first, or name a file with --evaluation.",
            problem=problem,
            fix=Fix.EVALUATE_MODEL,
        )
    return latest


def _race_type(params: TrainingParams | None, files: DeepRacerFiles) -> str:
    """The race type the model was set up for, from its training_params.yaml (DeepRacer's
    RACE_TYPE, as the console and DeepRacer-for-Cloud write it; none: a time trial): its
    evaluation drove among that race type's objects, so its laps go on that board."""
    if params is None:
        return TIME_TRIAL
    value = params.race_type.strip().lower().replace("-", "_")
    if value not in RACE_TYPES:
        choices = ", ".join(kind.upper() for kind in RACE_TYPES)
        raise LeagueError(
            f"{files.training_params}: RACE_TYPE must be one of {choices}, "
            f"not {params.race_type!r}."
        )
    return value


def _track(
    spec: str | None, params: TrainingParams | None, files: DeepRacerFiles, folder: Path
) -> Track:
    if spec is not None:
        try:
            return resolve_track(spec)
        except TrackError as error:
            raise LeagueError(str(error)) from None
    if params is None:
        raise LeagueError(
            f"{folder}: there is no training_params.yaml saying which track this is; "
            "name it with --track."
        )
    where = files.training_params
    try:
        world = training_world(params)  # DeepRacer on AWS's id and direction key too
    except DroaDirectionError as error:
        raise LeagueError(droa_direction_sentence(error)) from None
    try:
        found = resolve_track(world)
    except TrackError:
        problem = f"{where}: WORLD_NAME {params.world_name!r} is not a track racer-tui knows"
        raise LeagueError(
            f"{problem}; name the track with --track (a track name or a DeepRacer .npy file).",
            problem=problem,
            fix=Fix.IMPORT_TRACK,
        ) from None
    if params.track_hash and params.track_hash != found.content_hash:
        problem = (
            f"{where}: the track named {params.world_name!r} is not the one this model was "
            "set up on (its content differs)"
        )
        raise LeagueError(
            f"{problem}; name the right track with --track.", problem=problem, fix=Fix.IMPORT_TRACK
        )
    return found


def _action_summary(metadata: ModelMetadata) -> dict[str, Any]:
    space = metadata.action_space
    if space.kind == "discrete":
        speeds = [action.speed for action in space.actions]
        angles = [action.steering_angle for action in space.actions]
        return {
            "type": "discrete",
            "actions": len(space.actions),
            "speed": [min(speeds), max(speeds)],
            "steering": [min(angles), max(angles)],
        }
    return {
        "type": "continuous",
        "speed": list(space.speed_range),
        "steering": list(space.steering_range),
    }


def _training_summary(
    metrics: TrainingMetrics | None, params: TrainingParams | None, ours: Path | None = None
) -> dict[str, Any] | None:
    if metrics is None and params is None:
        return None
    summary: dict[str, Any] = {}
    if params is not None:
        summary["world_name"] = params.world_name
        summary["max_minutes"] = params.max_minutes
    if metrics is not None and metrics.episodes:
        training = [e for e in metrics.episodes if e.phase == "training"]
        first = min(e.start_time for e in metrics.episodes)
        last = max(e.metric_time for e in metrics.episodes)
        summary["episodes"] = len(training)
        summary["minutes"] = round(max(last - first, 0) / 60_000, 2)
        if ours is not None:
            # Our metrics run on the simulated clock of many cars at once: the trainer's
            # state says how long the training took.
            summary["minutes"] = _trained_minutes(ours, summary["minutes"])
        summary["best_completion"] = max(e.completion_percentage for e in metrics.episodes)
        summary["laps_completed"] = sum(
            1
            for e in training
            if e.completion_percentage >= 100 and e.episode_status != "Off track"
        )
    return summary


def _trained_minutes(folder: Path, fallback: float) -> float:

    state = ModelFolder(folder).training_state() or {}
    seconds = state.get("elapsed_seconds")
    if isinstance(seconds, int | float) and not isinstance(seconds, bool) and seconds >= 0:
        return round(seconds / 60.0, 2)
    return fallback


def _model_hash(
    folder: Path,
    *,
    source: str,
    metadata: ModelMetadata | None,
    hyperparameters: dict[str, float | int | str] | None,
    training: TrainingMetrics | None,
    trials: tuple[EvaluationTrial, ...],
) -> str:
    """What identifies the car: for our folders the garage's hash (metadata + weights), the
    same as the model's bundle; for DeepRacer downloads, what the files say about it."""
    if source == RACER_TUI:
        return ModelFolder(folder).content_hash()
    digest = hashlib.sha256(
        canonical_json(
            {
                "metadata": None if metadata is None else metadata.to_json(),
                "hyperparameters": hyperparameters,
            }
        )
    )
    if training is not None:
        digest.update(canonical_json(training.to_json()))
    else:  # nothing but the evaluation says which run this was
        digest.update(canonical_json([trial.__dict__ for trial in trials]))
    return digest.hexdigest()

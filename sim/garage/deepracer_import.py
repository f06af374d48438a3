"""`racer-tui model import PATH`: a DeepRacer model folder (or a bundle) into the garage.

Community tools (DeepRacer for Cloud, deepracer-utils) and the AWS console's downloads
lay the same files out differently; `sim.deepracer.files.locate_files` finds them. What a
DeepRacer folder lacks is filled in and said out loud: no reward function -> the
follow-the-centre-line template; a track racer-tui does not know -> the default track;
no hyperparameters -> DeepRacer's defaults. A folder with DeepRacer's own frozen weights
(`model/model_<N>.pb`) drives with them as the car would (`sim.garage.frozen_graph`); one
without, or imported `--untrained`, starts untrained. Its logs are kept in the DRfC
layout: training and evaluation metrics and their sim-traces, so the Garage shows the
training history and deepracer-utils reads the new folder (a copied racer-tui model folder
keeps its `policy.safetensors` too, once checked to be plain tensors).

Values outside racer-tui's ranges are never clamped: the error names the key, the file
and the allowed range, so the racer decides.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from sim.car_archive.errors import CarModelError
from sim.deepracer.car_look import car_look
from sim.deepracer.files import (
    MAX_METRICS_BYTES,
    SIM_TRACE_COLUMNS,
    DeepRacerFileError,
    DeepRacerFiles,
    EvaluationTrial,
    TrainingEpisode,
    TrainingMetrics,
    TrainingParams,
    default_hyperparameters,
    evaluation_stamp,
    locate_files,
    read_evaluation_metrics,
    read_hyperparameters,
    read_model_metadata,
    read_training_metrics,
    read_training_params,
    stamp_in,
    training_trace_path,
    write_evaluation_metrics,
    write_training_metrics,
)
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.remedies import Fix, Note
from sim.garage.bundle import MEMBER_LIMITS, check_safetensors
from sim.garage.folder import (
    POLICY_FILE,
    ModelError,
    ModelFolder,
    check_model_name,
    create_model,
)
from sim.garage.frozen_graph import folder_weights
from sim.garage.imported import ImportResult
from sim.garage.model_archive import LOG_JOB_TYPES, MAX_LOG_BYTES, download_name
from sim.garage.options import DEFAULT_MINUTES, DEFAULT_REWARD, DEFAULT_TRACK
from sim.physics.labels import DEEPRACER as DEEPRACER_PHYSICS
from sim.reward.function import check_reward_code, read_reward_file
from sim.reward.template_files import shipped_template
from sim.tracks.catalog import list_tracks
from sim.tracks.droa import (
    DROA_DIRECTION_KEY,
    DroaDirectionError,
    droa_direction_sentence,
    training_world,
)

if TYPE_CHECKING:
    from sim.garage.frozen_graph import FolderWeights

_T = TypeVar("_T")


def import_deepracer_folder(
    path: Path,
    name: str | None = None,
    track: str | None = None,
    *,
    untrained: bool = False,
    origin: Path | None = None,
) -> ImportResult:
    """Import a DeepRacer model folder as community tools and DeepRacer on AWS write it. A
    folder with DeepRacer's own frozen weights (`sim.garage.frozen_graph`) drives with them
    unless `untrained`, which starts it afresh so racer-tui can train it. `origin`: the
    archive the folder was unpacked from (`sim.garage.model_archive`), which names the
    model and is what the model says it came from."""
    root = Path(path).expanduser()
    source = origin if origin is not None else root
    files = locate_files(root)
    if files.model_metadata is None:
        raise ModelError(
            f"{source} has no model_metadata.json (looked in the folder and in model/); "
            "give the folder of a DeepRacer model."
        )
    chosen_name = name if name is not None else _default_name(root, origin)
    if name is None and not _usable_name(chosen_name):
        kind = "file" if origin is not None else "folder"
        problem = f"the {kind} name {chosen_name!r} cannot be a model name"
        raise ModelError(f"{problem}; give one with --name.", problem=problem, fix=Fix.RENAME)
    check_model_name(chosen_name)
    notes: list[str] = []
    metadata = _read(read_model_metadata, files.model_metadata)
    hyperparameters = _hyperparameters(files, notes)
    params = _read(read_training_params, files.training_params) if files.training_params else None
    world = _track(track, params, notes)
    look = car_look(params.extra) if params is not None else None
    logs = _logs(root)
    reward_source = _reward_source(files, notes)
    training = _training_metrics(files)
    evaluations = _evaluations(files)
    training_traces = _checked_traces(files.training_traces)
    policy = _racer_tui_policy(root)
    weights = None if policy is not None or untrained else _deepracer_weights(root, files, notes)
    if policy is None and weights is None:
        fresh = "it starts untrained"
        notes.append(
            Note(
                f"{fresh}: train it with `racer-tui train {chosen_name}`.",
                problem=fresh,
                fix=Fix.TRAIN_MODEL,
            )
        )

    def populate(folder: ModelFolder) -> None:
        if policy is not None:
            write_bytes_atomic(folder.policy_file, policy)
        if weights is not None:
            write_bytes_atomic(folder.car_archive_file, weights.archive)
        if training is not None:
            write_training_metrics(folder.training_metrics_file, training)
        for trace in training_traces:
            folder.training_trace_dir.mkdir(exist_ok=True)
            shutil.copyfile(trace, folder.path / training_trace_path(_iteration(trace)))
        for log in logs:
            target = folder.path / log.relative_to(root)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(log, target)
        for evaluation in evaluations:
            # Timed by DeepRacer's simulator: say so, so a submission of it is ranked apart.
            write_evaluation_metrics(
                folder.evaluation_metrics_file(evaluation.stamp),
                evaluation.trials,
                physics=DEEPRACER_PHYSICS,
            )
            if evaluation.trace is not None:
                target = folder.evaluation_trace_file(evaluation.stamp)
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(evaluation.trace, target)

    folder = create_model(
        chosen_name,
        track=world,
        metadata=metadata,
        hyperparameters=hyperparameters,
        reward_source=reward_source,
        max_minutes=params.max_minutes if params else DEFAULT_MINUTES,
        populate=populate,
        notes={"IMPORTED_FROM": str(source.resolve())},
        car_look=look,
    )
    return ImportResult(folder, tuple(notes))


def _default_name(root: Path, origin: Path | None) -> str:
    return download_name(origin) if origin is not None else root.resolve().name


def _logs(root: Path) -> list[Path]:
    """DeepRacer on AWS's job logs (`logs/<job type>/*.log`), kept as they are: plain files
    inside the folder, each of a size a log can have."""
    found: list[Path] = []
    for path in sorted(root.glob("logs/*/*.log")):
        if path.is_symlink() or path.parent.is_symlink() or not path.is_file():
            continue
        if path.parent.name not in LOG_JOB_TYPES:
            continue
        if path.stat().st_size > MAX_LOG_BYTES:
            raise ModelError(f"{path} is larger than a log can be; remove it and import again.")
        found.append(path)
    return found


def _deepracer_weights(root: Path, files: DeepRacerFiles, notes: list[str]) -> FolderWeights | None:
    """DeepRacer's own frozen weights, when the folder has them and they can drive here."""

    assert files.model_metadata is not None
    try:
        weights = folder_weights(root, files.model_metadata)
    except CarModelError as error:
        notes.append(f"its DeepRacer weights cannot drive in racer-tui: {error}")
        return None
    if weights is not None:
        notes.append(
            f"it drives with DeepRacer's own weights ({weights.graph.relative_to(root)}), run as "
            "a DeepRacer car runs them; it races and exports for the car but cannot be "
            "trained here: import it again leaving its weights behind (--untrained, or the "
            "import dialog's box) to train it in racer-tui."
        )
    return weights


def _racer_tui_policy(root: Path) -> bytes | None:
    """The trained weights of a copied racer-tui model folder, checked to be plain tensors."""
    path = root / POLICY_FILE
    if not path.is_file() or path.is_symlink():
        return None
    if path.stat().st_size > MEMBER_LIMITS[POLICY_FILE]:
        raise ModelError(f"{path} is too large to be a policy file.")
    data = path.read_bytes()
    check_safetensors(data, str(path))
    return data


def _usable_name(name: str) -> bool:
    try:
        check_model_name(name)
    except ModelError:
        return False
    return True


def _read(reader: Callable[[Path], _T], path: Path) -> _T:
    """Read a DeepRacer file; out-of-range values are reported, never clamped."""
    try:
        return reader(path)
    except DeepRacerFileError as error:
        raise ModelError(f"{str(error).rstrip('.')}; edit the file and import again.") from None


def _hyperparameters(files: DeepRacerFiles, notes: list[str]) -> dict[str, float | int | str]:
    if files.hyperparameters is None:
        notes.append("it has no hyperparameters.json: DeepRacer's defaults are used.")
        return default_hyperparameters()
    return _read(read_hyperparameters, files.hyperparameters)


def _track(explicit: str | None, params: TrainingParams | None, notes: list[str]) -> str:

    if explicit is not None:
        return explicit  # create_model checks it before anything is written
    world = params.world_name if params else None
    if params is not None:
        try:
            world = training_world(params)  # DeepRacer on AWS's id and direction key too
        except DroaDirectionError as error:
            raise ModelError(droa_direction_sentence(error)) from None
        if world != params.world_name:
            direction = "clockwise" if world.endswith("_cw") else "counter-clockwise"
            said = json.dumps(params.extra[DROA_DIRECTION_KEY])  # as YAML writes it
            notes.append(
                f"DeepRacer on AWS trained it on {params.world_name} {direction} "
                f"({DROA_DIRECTION_KEY}: {said}): it is set up on {world}."
            )
    if world is not None and world in {info.name for info in list_tracks()}:
        return world
    where = f"it trained on {world!r}, which" if world else "its track"
    problem = f"{where} is not a racer-tui track: it is set up on {DEFAULT_TRACK}"
    notes.append(
        Note(
            f"{problem}; choose another with --track (import DeepRacer .npy tracks with "
            "`racer-tui tracks import`).",
            problem=problem,
            fix=Fix.CHOOSE_TRACK,
        )
    )
    return DEFAULT_TRACK


def _reward_source(files: DeepRacerFiles, notes: list[str]) -> str:
    if files.reward_function is None:
        notes.append(
            f"it has no reward_function.py: the {DEFAULT_REWARD} template is used instead."
        )
        return shipped_template(DEFAULT_REWARD)
    # Someone else's code: checked, never run here; it runs when the racer trains.
    source = read_reward_file(files.reward_function)
    check_reward_code(source, str(files.reward_function))  # names the file and line
    notes.append(
        "its reward_function.py was checked but not run: it runs, contained (time, memory, "
        "no programs; on Linux none of your files), when you train this model (or check "
        "it), so read it first if it is not yours."
    )
    return source


def _training_metrics(files: DeepRacerFiles) -> TrainingMetrics | None:
    """All training metrics files as one `training.json` (DeepRacer may split a job)."""
    if not files.training_metrics:
        return None
    episodes: list[TrainingEpisode] = []
    for path in files.training_metrics:
        episodes.extend(_read(read_training_metrics, path).episodes)
    return TrainingMetrics(tuple(episodes))


@dataclass(frozen=True)
class _Evaluation:
    stamp: str  # DRfC's 14-digit name for it in the new folder
    trials: tuple[EvaluationTrial, ...]
    trace: Path | None  # its sim-trace, when the download has one


def _evaluations(files: DeepRacerFiles) -> list[_Evaluation]:
    """Each evaluation with its DeepRacer timestamp (the file's time otherwise, moved on a
    second when taken: DRfC names hold 14 digits) and the sim-trace of the same stamp. A
    console download of one evaluation keeps its sim-trace without a stamp."""
    traces = dict(files.evaluation_traces)
    unstamped = [path for stamp, path in files.evaluation_traces if stamp is None]
    found: list[_Evaluation] = []
    used: set[str] = set()
    for path in files.evaluation_metrics:
        trials = _read(read_evaluation_metrics, path)
        original = stamp_in(path.name)
        when = datetime.fromtimestamp(path.stat().st_mtime, UTC)
        stamp = original or evaluation_stamp(when)
        while stamp in used:
            when = datetime.strptime(stamp, "%Y%m%d%H%M%S").replace(tzinfo=UTC)
            stamp = evaluation_stamp(when + timedelta(seconds=1))
        used.add(stamp)
        trace = traces.get(original) if original else None
        if trace is None and len(files.evaluation_metrics) == 1 and len(unstamped) == 1:
            trace = unstamped[0]
        found.append(_Evaluation(stamp, trials, trace))
    for evaluation in found:
        if evaluation.trace is not None:
            _checked_traces([evaluation.trace])
    return found


def _checked_traces(paths: tuple[Path, ...] | list[Path]) -> list[Path]:
    """Sim-trace files worth copying: DeepRacer's columns in the header (newer simapps add
    some after them), of a size a trace can have; anything else stops the import, naming
    the file. Training traces must be numbered, as deepracer-utils reads the number."""
    known = list(SIM_TRACE_COLUMNS[:16])  # the last, pause_duration, is missing in old ones
    for path in paths:
        if path.stat().st_size > MAX_METRICS_BYTES:
            raise ModelError(
                f"{path} is larger than a sim-trace can be; remove it and import again."
            )
        with path.open("rb") as handle:
            header = handle.readline(4096).decode("utf-8", errors="replace").strip()
        if header.split(",")[:16] != known:
            raise ModelError(
                f"{path} is not a DeepRacer sim-trace CSV (unexpected header); remove it "
                "and import again."
            )
    return [path for path in paths if path.name.split("-", 1)[0].isdigit()]


def _iteration(path: Path) -> int:
    return int(path.name.split("-", 1)[0])

"""Moving model folders of racer-tui's old flat layout into deepracer-for-cloud's layout.

Until the model folder became a DRfC model folder, racer-tui kept everything at the top
(`model_metadata.json`, `hyperparameters.json`, `training.json`, `evaluation-<stamp>.json`,
`sim-trace/training/`, `sim-trace/evaluation/`). The first open of such a folder moves
each file to its DRfC place; nothing is deleted unless an identical copy is already there.

Crash safety: the whole plan is written first (`.migration.json`, atomically), then carried
out one rename at a time, and removed last. A process killed at any point leaves a folder
that opens (every file is at its old place or its new one), and the next open finishes the
same plan. A lock on the folder keeps two processes from migrating it at once.

Where the old files had no DRfC equivalent they are kept aside, not dropped: the old
training sim-traces (one car, a clock that did not advance) go to `old-layout/`, where
deepracer-utils does not look, and so does anything that would overwrite a different file.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from dataclasses import replace
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

from sim.deepracer.files import (
    HYPERPARAMETERS,
    HYPERPARAMETERS_PATH,
    LEGACY_EVALUATION_GLOB,
    LEGACY_SIM_TRACE_DIR,
    LEGACY_TRAINING_METRICS,
    MODEL_METADATA,
    MODEL_METADATA_PATH,
    TRAINING_METRICS_PATH,
    DeepRacerFileError,
    default_hyperparameters,
    evaluation_metrics_path,
    evaluation_stamp,
    evaluation_trace_path,
    read_hyperparameters,
    read_training_metrics,
    stamp_in,
    training_metrics_text,
)
from sim.foundation.atomic import write_text_atomic
from sim.foundation.remedies import RemedyError

JOURNAL = ".migration.json"
OLD_LAYOUT_DIR = "old-layout"


class MigrationError(RemedyError):
    """A folder that could not be moved into the new layout; the message says what to do."""


def needs_migration(folder: Path) -> bool:
    """Whether `folder` is an old flat racer-tui folder, or one whose move was cut short.

    Its `model_metadata.json` at the top says so (it moves last); a folder without it is
    left alone, since `sim-trace/` or `hyperparameters.json` alone may be anyone's files
    (the AWS console's log download has a `sim-trace/` of its own)."""
    return (folder / JOURNAL).is_file() or (folder / MODEL_METADATA).is_file()


def migrate_folder(folder: Path) -> bool:
    """Move an old-layout model folder into the DRfC layout; True if anything moved."""
    if not needs_migration(folder):
        return False
    try:
        with _locked(folder):
            if not needs_migration(folder):  # another process finished it meanwhile
                return False
            journal = folder / JOURNAL
            moves = _read_plan(journal)
            if moves is None:
                moves = _plan(folder)
                write_text_atomic(journal, json.dumps({"moves": moves}, indent=1) + "\n")
            for move in moves:
                _carry_out(folder, move)
            _remove_empty_dirs(folder / LEGACY_SIM_TRACE_DIR)
            journal.unlink(missing_ok=True)
    except OSError as error:
        reason = error.strerror or str(error)
        raise MigrationError(
            f"{folder}: cannot move it into the new model folder layout ({reason}); "
            "fix the folder's permissions or free some disk space, then open it again."
        ) from None
    return True


# --- the plan ----------------------------------------------------------------------------


def _plan(folder: Path) -> list[dict[str, Any]]:
    """Every move, in order: (from, to) relative to the folder; metadata last, since its
    new place is what makes the folder open as a model of the new layout."""
    moves: list[dict[str, Any]] = []
    taken: set[str] = set()

    def move(source: str, target: str, **extra: Any) -> None:
        if (folder / target).exists() or target in taken:
            target = _aside(folder, source, taken)
        taken.add(target)
        moves.append({"from": source, "to": target, **extra})

    if (folder / HYPERPARAMETERS).is_file():
        move(HYPERPARAMETERS, HYPERPARAMETERS_PATH)
    if (folder / LEGACY_TRAINING_METRICS).is_file():
        move(LEGACY_TRAINING_METRICS, TRAINING_METRICS_PATH, renumber=True)
    traces = folder / LEGACY_SIM_TRACE_DIR / "evaluation"
    stamps: set[str] = set()
    for path in sorted(folder.glob(LEGACY_EVALUATION_GLOB)):
        if not path.is_file():
            continue
        old = path.name.removeprefix("evaluation-").removesuffix(".json")
        stamp = _free_stamp(folder, stamp_in(old) or _file_stamp(path), stamps)
        move(path.name, evaluation_metrics_path(stamp))
        trace = traces / f"{old}-iteration.csv"
        if trace.is_file():
            move(_relative(folder, trace), evaluation_trace_path(stamp))
    planned = {move["from"] for move in moves}
    for path in sorted(p for p in (folder / LEGACY_SIM_TRACE_DIR).rglob("*") if p.is_file()):
        source = _relative(folder, path)
        if source in planned:
            continue
        stem = path.name.removesuffix("-iteration.csv")
        if path.parent == traces and stem != path.name:
            stamp = _free_stamp(folder, stamp_in(stem) or _file_stamp(path), stamps)
            move(source, evaluation_trace_path(stamp))
        else:  # old training traces and anything unexpected: kept where nothing reads them
            move(source, f"{OLD_LAYOUT_DIR}/{source}")
    if (folder / MODEL_METADATA).is_file():
        move(MODEL_METADATA, MODEL_METADATA_PATH)
    return moves


def _free_stamp(folder: Path, stamp: str, used: set[str]) -> str:
    """`stamp`, or the next second that no evaluation of this folder uses yet (DRfC names
    hold exactly 14 digits, so two evaluations in one second cannot share one)."""
    when = datetime.strptime(stamp, "%Y%m%d%H%M%S").replace(tzinfo=UTC)
    while True:
        candidate = evaluation_stamp(when)
        busy = (folder / evaluation_metrics_path(candidate)).exists() or (
            folder / evaluation_trace_path(candidate)
        ).parent.parent.exists()
        if candidate not in used and not busy:
            used.add(candidate)
            return candidate
        when += timedelta(seconds=1)


def _file_stamp(path: Path) -> str:
    return evaluation_stamp(datetime.fromtimestamp(path.stat().st_mtime, UTC))


def _aside(folder: Path, source: str, taken: set[str]) -> str:
    target, n = f"{OLD_LAYOUT_DIR}/{source}", 1
    while (folder / target).exists() or target in taken:
        n += 1
        target = f"{OLD_LAYOUT_DIR}/{n}/{source}"
    return target


def _relative(folder: Path, path: Path) -> str:
    return path.relative_to(folder).as_posix()


def _read_plan(journal: Path) -> list[dict[str, Any]] | None:
    """The plan of a migration that was cut short, if there is a readable one."""
    try:
        data = json.loads(journal.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None  # written atomically, so this is someone else's file: plan afresh
    moves = data.get("moves") if isinstance(data, dict) else None
    if not isinstance(moves, list) or not all(_is_move(m) for m in moves):
        return None
    return moves


def _is_move(move: object) -> bool:
    if not isinstance(move, dict):
        return False
    paths = [move.get("from"), move.get("to")]
    return all(
        isinstance(p, str) and p and not p.startswith("/") and ".." not in Path(p).parts
        for p in paths
    )


# --- carrying it out -----------------------------------------------------------------------


def _carry_out(folder: Path, move: dict[str, Any]) -> None:
    source, target = folder / move["from"], folder / move["to"]
    if not source.exists():
        return  # done before the process was stopped
    if move.get("renumber"):
        _renumber_trials(folder, source)
    target.parent.mkdir(parents=True, exist_ok=True)
    if target.exists():  # appeared since the plan was made: keep both
        if source.is_file() and target.is_file() and source.read_bytes() == target.read_bytes():
            source.unlink()
            return
        target = folder / _aside(folder, move["from"], set())
        target.parent.mkdir(parents=True, exist_ok=True)
    os.replace(source, target)


def _renumber_trials(folder: Path, path: Path) -> None:
    """Old training.json numbered `trial` like `episode`; DeepRacer counts trials within an
    iteration of num_episodes_between_training episodes, which deepracer-utils'
    TrainingMetrics reads to find the iterations. Rewriting is idempotent, so a crash
    before the rename only repeats it."""
    try:
        metrics = read_training_metrics(path)
    except DeepRacerFileError:
        return  # moved as it is: a file we cannot read is still the racer's
    per_iteration = int(_episodes_per_iteration(folder))
    episodes = tuple(
        replace(row, trial=(row.episode - 1) % per_iteration + 1 if row.episode > 0 else 0)
        for row in metrics.episodes
    )
    if episodes != metrics.episodes:
        write_text_atomic(path, training_metrics_text(replace(metrics, episodes=episodes)))


def _episodes_per_iteration(folder: Path) -> float | int | str:
    for candidate in (folder / HYPERPARAMETERS, folder / HYPERPARAMETERS_PATH):
        if candidate.is_file():
            try:
                return read_hyperparameters(candidate)["num_episodes_between_training"]
            except DeepRacerFileError:
                break
    return default_hyperparameters()["num_episodes_between_training"]


def _remove_empty_dirs(root: Path) -> None:
    if not root.is_dir() or root.is_symlink():
        return
    for path in sorted(root.rglob("*"), key=lambda p: len(p.parts), reverse=True):
        if path.is_dir() and not path.is_symlink():
            with contextlib.suppress(OSError):
                path.rmdir()
    with contextlib.suppress(OSError):
        root.rmdir()


@contextlib.contextmanager
def _locked(folder: Path) -> Iterator[None]:
    """An exclusive lock on the folder itself while it migrates (released if the process
    dies); where the platform has no flock, migrations simply do not overlap in practice."""
    try:
        import fcntl  # noqa: PLC0415 (not every platform has fcntl)
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)

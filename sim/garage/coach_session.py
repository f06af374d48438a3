"""Coaching a model: its lap, read from its latest evaluation, against the limit lap of its
own action space on its track, sector by sector.

The front ends (`racer-tui coach`, the app's Coach view) call `coach_model` for a garage
model or a DeepRacer model folder, or `coach_path` for any lap they already hold (a race's,
a replay's).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from sim.coach.lap_analysis import (
    DrivenPath,
    LapAnalysisError,
    LapReport,
    analyse_lap,
    path_of_race_lap,
    path_of_trial,
)
from sim.coach.limit_lap import LimitLap, limit_lap
from sim.coach.sectors import Sector, track_sectors
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.files import (
    DeepRacerFileError,
    read_evaluation_metrics,
    read_sim_trace,
    stamp_in,
)
from sim.foundation.remedies import Fix
from sim.garage.folder import ModelError, ModelFolder, open_model
from sim.race.result import RaceResult
from sim.tracks.track import Track

BEST = "best"
# A sim-trace whose track_len is within this share of the model's track's length was driven
# there (DeepRacer's own length of a track may differ from racer-tui's by centimetres).
_SAME_LENGTH = 0.02


@dataclass(frozen=True)
class Coaching:
    """A lap explained: the report, and the limit laps it is measured against."""

    track: Track
    report: LapReport
    limit: LimitLap  # within the model's action space
    car_limit: LimitLap  # racer-tui's car, any action
    sectors: tuple[Sector, ...]
    path: DrivenPath


def coach_path(track: Track, path: DrivenPath, space: ActionSpace | None = None) -> Coaching:
    """`path` (one lap of a car on `track`) against the limit lap within `space`."""
    limit = limit_lap(track, space=space)
    sectors = tuple(track_sectors(track, limit))
    report = analyse_lap(track, limit, sectors, path)
    return Coaching(track, report, limit, limit_lap(track), sectors, path)


def coach_model(folder: ModelFolder, lap: str = BEST) -> Coaching:
    """The model's lap `lap` ("best", or a trial number) of its latest evaluation."""
    files = folder.evaluation_files()
    if not files and not folder.has_policy():
        problem = f"{folder.name} has not been trained, so it has no lap to coach"
        raise LapAnalysisError(
            f"{problem}; train it, then evaluate it (racer-tui train {folder.name}).",
            problem=problem,
            fix=Fix.TRAIN_MODEL,
        )
    if not files:
        problem = f"{folder.name} has no evaluation to coach"
        raise LapAnalysisError(
            f"{problem}; evaluate it first (racer-tui evaluate {folder.name}).",
            problem=problem,
            fix=Fix.EVALUATE_MODEL,
        )
    metrics = files[-1]
    stamp = stamp_in(metrics.name)
    trace_file = folder.evaluation_trace_file(stamp) if stamp else None
    if trace_file is None or not trace_file.is_file():
        raise LapAnalysisError(
            f"{folder.name}'s latest evaluation kept no sim-trace, so its laps cannot be "
            "followed; evaluate it again."
        )
    trials = read_evaluation_metrics(metrics)
    laps = {
        number: trial.elapsed_time_in_milliseconds / 1000.0
        for number, trial in enumerate(trials, start=1)
        if trial.completion_percentage >= 100.0
    }
    if not laps:
        raise LapAnalysisError(
            f"no trial of {folder.name}'s latest evaluation completed its lap; train it "
            "further, then evaluate it again."
        )
    if lap == BEST:
        number = min(laps, key=lambda n: laps[n])
    else:
        number = _trial_number(lap, len(trials))
        if number not in laps:
            raise LapAnalysisError(f"trial {number} of the evaluation did not complete its lap.")
    rows = read_sim_trace(trace_file)
    track = folder.track()
    if rows and abs(rows[0].track_len - track.length) > _SAME_LENGTH * track.length:
        raise LapAnalysisError(
            f"{folder.name}'s latest evaluation was driven on another track than its own "
            f"({track.name}); evaluate it on {track.name} to coach it there."
        )
    episodes = sorted({row.episode for row in rows})
    if len(episodes) < number:
        raise LapAnalysisError(f"the evaluation's sim-trace holds no trial {number}.")
    path = replace(path_of_trial(rows, episodes[number - 1], laps[number]), label=f"trial {number}")
    return coach_path(track, path, folder.metadata().action_space)


def coach_race(track: Track, result: RaceResult) -> Coaching:
    """The fastest counted lap of a race or replay. Its limit lap is within the action space
    of the garage model that drove it, when that model is here unchanged; else any action."""
    best = result.best_lap
    if best is None:
        raise LapAnalysisError("no lap of this race counted, so it has no lap to coach.")
    if result.trace is None:
        raise LapAnalysisError(
            "this race kept no trace of its laps, so they cannot be followed; race it again."
        )
    path = path_of_race_lap(result.trace, best.number, official=best.time_seconds)
    return coach_path(track, path, _racing_model_space(result))


def _racing_model_space(result: RaceResult) -> ActionSpace | None:
    try:
        folder = open_model(result.model_name)
        if folder.content_hash() == result.model_hash:
            return folder.metadata().action_space
    except (ModelError, DeepRacerFileError, OSError):
        pass  # the reference driver, or a model not in this garage: the car's own limit
    return None


def _trial_number(text: str, trials: int) -> int:
    try:
        number = int(text)
    except ValueError:
        number = 0
    if not 1 <= number <= trials:
        raise LapAnalysisError(
            f"--lap takes 'best' or a trial number from 1 to {trials}, not {text!r}."
        )
    return number

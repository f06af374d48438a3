"""DeepRacer-style evaluation: time-trial trials, one lap each from the start line.

Trials run side by side as cars of one `TrackSimulation` (they never touch each other),
driven by any `Driver` (a trained policy, or the reference driver). A trial ends the way a
DeepRacer evaluation trial does: lap complete, off track, crashed, reversed, immobilized,
or out of time. Lap times are interpolated inside the last 1/15 s step, as the reference
lap is, so they are not quantised.

The simulator is deterministic, so trial 1 starts exactly on the start line and the
others start a few centimetres and degrees off it (seeded): five identical trials would
say nothing about how robust a policy is, and a real car is never placed exactly.

No torch at module level: `evaluate_model` loads the policy driver only when it runs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sim.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec
from sim.deepracer_files import (
    EvaluationTrial,
    SimTraceRow,
    evaluation_file_name,
    trace_status,
    write_evaluation_metrics,
    write_sim_trace,
)
from sim.simulation import EpisodeRules, EpisodeStatus, TrackSimulation
from sim.track import Track

if TYPE_CHECKING:
    from sim.garage.folder import ModelFolder
    from sim.race.driver import Driver

DEFAULT_TRIALS = 5
MAX_TRIALS = 100
TRIAL_SECONDS = 120.0  # a trial still running after this is "Time Up"
START_OFFSET_M = 0.03  # largest lateral start offset of trials after the first
START_YAW_DEG = 3.0  # largest heading error at the start of trials after the first


@dataclass(frozen=True)
class TrialResult:
    trial: int  # from 1
    status: str  # DeepRacer's status label
    progress: float  # percent of the lap, 0..100
    seconds: float  # time the trial ran (the lap time when it completed)

    @property
    def lap_time(self) -> float | None:
        return self.seconds if self.status == EpisodeStatus.LAP_COMPLETE else None


@dataclass(frozen=True)
class EvaluationReport:
    track: str
    trials: tuple[TrialResult, ...]
    metrics_file: Path | None = None

    @property
    def laps(self) -> int:
        return sum(1 for trial in self.trials if trial.lap_time is not None)

    @property
    def mean_progress(self) -> float:
        return float(np.mean([trial.progress for trial in self.trials])) if self.trials else 0.0

    @property
    def best_lap(self) -> float | None:
        laps = [trial.lap_time for trial in self.trials if trial.lap_time is not None]
        return min(laps) if laps else None

    @property
    def mean_lap(self) -> float | None:
        laps = [trial.lap_time for trial in self.trials if trial.lap_time is not None]
        return float(np.mean(laps)) if laps else None


def start_poses(trials: int, seed: int = 0) -> list[tuple[float, float]]:
    """(lateral offset m, heading error deg) of each trial's start; trial 1 is exact."""
    rng = np.random.default_rng(seed)
    poses = [(0.0, 0.0)]
    for _ in range(1, trials):
        poses.append(
            (
                float(rng.uniform(-START_OFFSET_M, START_OFFSET_M)),
                float(rng.uniform(-START_YAW_DEG, START_YAW_DEG)),
            )
        )
    return poses


def run_trials(
    driver: Driver,
    track: Track,
    trials: int = DEFAULT_TRIALS,
    *,
    car: CarSpec = DEEPRACER_CAR,
    max_seconds: float = TRIAL_SECONDS,
    seed: int = 0,
    trace: list[SimTraceRow] | None = None,
) -> list[TrialResult]:
    """Drive `trials` one-lap trials from the start line with `driver`.

    When `trace` is given, every step of every trial is appended to it as a sim-trace row
    (the trial number in the `episode` column, from 0 as DeepRacer writes it).
    """
    if not 1 <= trials <= MAX_TRIALS:
        raise ValueError(f"the number of trials must be between 1 and {MAX_TRIALS}.")
    max_steps = max(1, int(max_seconds * STEP_HZ))
    sim = TrackSimulation(track, trials, car=car, rules=EpisodeRules(max_steps=max_steps))
    sim.reset_cars(range(trials), [0.0] * trials)
    for index, (offset, yaw_error) in enumerate(start_poses(trials, seed)):
        if index == 0:
            continue
        sim.place(index, 0.0, offset)
        yaw = float(sim.fleet.yaw[index]) + math.radians(yaw_error)
        sim.put(index, float(sim.fleet.x[index]), float(sim.fleet.y[index]), yaw)
    driver.reset(sim)
    length = track.length
    previous = np.zeros(trials)
    seconds = np.full(trials, math.nan)
    status: list[str] = [str(EpisodeStatus.IN_PROGRESS)] * trials
    progress = np.zeros(trials)
    for _ in range(max_steps):
        running = np.isnan(seconds)
        if not running.any():
            break
        x, y, heading = sim.fleet.x.copy(), sim.fleet.y.copy(), sim.heading_deg
        action = driver.act(sim)
        sim.apply(action.steering_deg, action.speed)
        travelled = sim.travelled / length * 100.0
        for index in np.flatnonzero(running).tolist():
            state = sim.status[index]
            steps = int(sim.steps[index])
            if trace is not None:
                trace.append(
                    _trace_row(
                        sim,
                        index,
                        x=x,
                        y=y,
                        heading=heading,
                        action_index=action.action_index,
                        steps=steps,
                        state=state,
                    )
                )
            if state == EpisodeStatus.IN_PROGRESS:
                previous[index] = travelled[index]
                continue
            status[index] = str(state)
            progress[index] = float(sim.progress[index])
            if state == EpisodeStatus.LAP_COMPLETE:
                step_gain = max(travelled[index] - previous[index], 1e-9)
                fraction = min(max((100.0 - previous[index]) / step_gain, 0.0), 1.0)
                seconds[index] = (steps - 1 + fraction) * STEP_SECONDS
            else:
                seconds[index] = steps * STEP_SECONDS
    for index in np.flatnonzero(np.isnan(seconds)).tolist():
        status[index] = str(EpisodeStatus.TIME_UP)
        progress[index] = float(sim.progress[index])
        seconds[index] = float(sim.steps[index]) * STEP_SECONDS
    return [
        TrialResult(trial=i + 1, status=status[i], progress=float(progress[i]), seconds=seconds[i])
        for i in range(trials)
    ]


def _trace_row(
    sim: TrackSimulation,
    car: int,
    *,
    x: np.ndarray,
    y: np.ndarray,
    heading: np.ndarray,
    action_index: np.ndarray,
    steps: int,
    state: str,
) -> SimTraceRow:
    done = state != EpisodeStatus.IN_PROGRESS
    return SimTraceRow(
        episode=car,
        steps=steps,
        x=float(x[car]),
        y=float(y[car]),
        yaw=float(heading[car]),
        steer=float(sim.steering_cmd[car]),
        throttle=float(sim.speed_cmd[car]),
        action=int(action_index[car]),
        reward=0.0,
        done=done,
        all_wheels_on_track=bool(sim.wheels_on[car].all()),
        progress=float(sim.progress[car]),
        closest_waypoint=int(sim.segment[car]),
        track_len=float(sim.track.length),
        tstamp=steps * STEP_SECONDS,
        episode_status="prepare" if steps == 1 else trace_status(state),
    )


_COUNTS = {
    EpisodeStatus.CRASHED: "crash_count",
    EpisodeStatus.IMMOBILIZED: "immobilized_count",
    EpisodeStatus.OFF_TRACK: "off_track_count",
    EpisodeStatus.REVERSED: "reversed_count",
}


def evaluation_trials(results: Sequence[TrialResult]) -> list[EvaluationTrial]:
    """Results as DeepRacer EvaluationMetrics rows, trials back to back from time 0."""
    rows: list[EvaluationTrial] = []
    clock = 0
    for result in results:
        elapsed = round(result.seconds * 1000)
        counts = {name: 0 for name in _COUNTS.values()}
        key = _COUNTS.get(EpisodeStatus(result.status)) if result.status in _STATUS_SET else None
        if key is not None:
            counts[key] = 1
        rows.append(
            EvaluationTrial(
                completion_percentage=round(result.progress, 2),
                metric_time=clock + elapsed,
                start_time=clock,
                elapsed_time_in_milliseconds=elapsed,
                episode_status=result.status,
                trial=result.trial,
                **counts,
            )
        )
        clock += elapsed
    return rows


_STATUS_SET = {status.value for status in EpisodeStatus}


def evaluate_model(
    folder: ModelFolder,
    *,
    track: Track | None = None,
    trials: int = DEFAULT_TRIALS,
    seed: int = 0,
) -> EvaluationReport:
    """Evaluate a garage model's policy and write `evaluation-<stamp>.json` (DeepRacer's
    EvaluationMetrics) and `sim-trace/evaluation/<stamp>-iteration.csv` into its folder."""
    from sim.training.policy import driver_for_model

    driver = driver_for_model(folder)
    chosen = track if track is not None else folder.track()
    rows: list[SimTraceRow] = []
    results = run_trials(driver, chosen, trials, seed=seed, trace=rows)
    now = datetime.now(UTC)
    name = evaluation_file_name(now)
    path = folder.path / name
    # Two evaluations within one second must not overwrite each other.
    suffix = 1
    while path.exists():
        path = folder.path / name.replace(".json", f"{suffix:02d}.json")
        suffix += 1
    write_evaluation_metrics(path, evaluation_trials(results))
    stamp = path.stem.removeprefix("evaluation-")
    write_sim_trace(folder.sim_trace_dir / "evaluation" / f"{stamp}-iteration.csv", rows)
    return EvaluationReport(track=chosen.name, trials=tuple(results), metrics_file=path)

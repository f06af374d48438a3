"""DeepRacer-style evaluation: time-trial trials, one lap each from the start line.

Trials run side by side as cars of one `TrackSimulation` (they never touch each other),
driven by any `Driver` (a trained policy, or the reference driver). A trial ends the way a
DeepRacer evaluation trial does: lap complete, off track, crashed, reversed, immobilized,
or out of time. Lap times are interpolated inside the last 1/15 s step, as the reference
lap is, so they are not quantised.

The simulator is deterministic, so trial 1 starts exactly on the start line and the
others start a few centimetres and degrees off it (seeded): five identical trials would
say nothing about how robust a policy is, and a real car is never placed exactly.

Off-tracks: a racer's evaluation (`evaluate_model`) puts the car back and adds DeepRacer's
penalty (2 s for an off-track, `sim.physics.resets`) to the trial's time, as many times as the trial
needs; training's own evaluations end a trial at its first off-track, as DeepRacer training
does (`sim.training.trial_resets`).

No torch at module level: `evaluate_model` loads the policy driver only when it runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sim.deepracer.files import (
    PREPARE_STATUS,
    SIM_TRACE_COLUMNS,
    DeepRacerFileError,
    EvaluationTrial,
    SimTraceColumns,
    evaluation_stamp,
    sim_trace_lines,
    trace_status,
    write_evaluation_metrics,
)
from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.atomic import write_text_atomic
from sim.garage.folder import ModelError
from sim.physics.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.physics.objects.reading import race_settings
from sim.physics.objects.settings import RaceSettings, RaceType
from sim.physics.resets import ResetRules
from sim.physics.simulation import EpisodeRules, TrackSimulation, let_other_threads_run
from sim.tracks.track import Track
from sim.training.logbook import closest_waypoint
from sim.training.trace_pose import RowPoses
from sim.training.trial_resets import EVALUATION_RESETS, TRAINING_RESETS, TrialResets

if TYPE_CHECKING:
    from sim.garage.folder import ModelFolder
    from sim.race.driver import Driver

DEFAULT_TRIALS = 5
MAX_TRIALS = 100
TRIAL_SECONDS = 120.0  # a trial still running after this is "Time Up"
PROGRESS_EVERY_STEPS = STEP_HZ  # steps between progress reports: one simulated second
START_OFFSET_M = 0.03  # largest lateral start offset of trials after the first
START_YAW_DEG = 3.0  # largest heading error at the start of trials after the first


@dataclass(frozen=True)
class TrialResult:
    trial: int  # from 1
    status: str  # DeepRacer's status label
    progress: float  # percent of the lap, 0..100
    seconds: float  # time the trial ran (the lap time when it completed), penalties included
    resets: tuple[str, ...] = ()  # statuses the car was put back after, in order
    penalty_seconds: float = 0.0  # of `seconds`, the penalty holds of those resets

    @property
    def lap_time(self) -> float | None:
        return self.seconds if self.status == EpisodeStatus.LAP_COMPLETE else None

    @property
    def off_tracks(self) -> int:
        """Times the car left the track: each reset after one, and an off-track ending."""
        events = (*self.resets, self.status)
        return sum(1 for event in events if event == EpisodeStatus.OFF_TRACK)


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


class TrialTrace:
    """Every step of every trial: DeepRacer's point 0.14 m ahead of the car, heading, the
    step's action, all four wheels on the road, progress and status, the pose as
    DeepRacer's row timing shows it (`sim.training.trace_pose`). `columns` lays the trials
    end to end as DeepRacer runs them, each trial's clock holding still for the penalty
    after a reset (the row that went off says how long in `pause_duration`, as simapp's
    does), so the trace's time is the trial's."""

    def __init__(self) -> None:
        self._steps: list[tuple[NDArray[np.intp], NDArray[np.float64], list[str]]] = []
        self._poses = RowPoses()

    def before_step(self, sim: TrackSimulation) -> None:
        """Note where every car is as the step begins (a row's pose is one row late)."""
        self._poses.before_step(sim)

    def record(
        self,
        sim: TrackSimulation,
        cars: NDArray[np.intp],
        action: NDArray[Any],
        penalty: NDArray[np.float64],
    ) -> None:
        """The step just taken by `cars`; `penalty` is each trial's hold time before it."""
        waypoints = np.asarray(sim.track.center, dtype=np.float64)
        pose = self._poses.after_step(sim)
        values = np.column_stack(
            (
                sim.steps,
                pose.ahead[:, 0],
                pose.ahead[:, 1],
                pose.heading_deg,
                sim.steering_cmd,
                sim.speed_cmd,
                action,
                pose.wheels_on,
                pose.progress,
                closest_waypoint(pose.ahead, pose.segment, waypoints),
                penalty,
            )
        )[cars]
        self._steps.append((cars.copy(), values, [str(sim.status[car]) for car in cars]))

    def columns(self, trials: Sequence[EvaluationTrial], track_length: float) -> SimTraceColumns:
        """Trial k's rows as episode k - 1, its clock starting at the trial's start_time."""
        cars = np.concatenate([cars for cars, _, _ in self._steps])
        values = np.concatenate([values for _, values, _ in self._steps])
        states = [state for _, _, statuses in self._steps for state in statuses]
        order = np.lexsort((values[:, 0], cars))  # trial by trial, step by step
        cars, values = cars[order], values[order]
        steps = values[:, 0].astype(np.int64)
        starts = np.array([trial.start_time / 1000.0 for trial in trials])
        done = np.append(cars[1:] != cars[:-1], True)
        statuses = [
            PREPARE_STATUS if step == 1 and not last else trace_status(states[i])
            for i, last, step in zip(order.tolist(), done.tolist(), steps.tolist(), strict=True)
        ]
        held = values[:, 10]
        pause = np.where(done, 0.0, np.append(np.diff(held), 0.0))
        return SimTraceColumns(
            episode=cars.astype(np.int64),
            steps=steps,
            x=values[:, 1],
            y=values[:, 2],
            yaw=values[:, 3],
            steer=values[:, 4],
            throttle=values[:, 5],
            action=values[:, 6].astype(np.int64),
            reward=np.zeros(len(cars)),
            done=done,
            all_wheels_on_track=values[:, 7] > 0.5,
            progress=values[:, 8],
            closest_waypoint=values[:, 9].astype(np.int64),
            track_len=track_length,
            # A trial's clock runs from its start: its step k ends k/15 s after it, plus
            # the holds it served before.
            tstamp=starts[cars] + steps * STEP_SECONDS + held,
            episode_status=statuses,
            pause_duration=pause,
        )


def run_trials(
    driver: Driver,
    track: Track,
    trials: int = DEFAULT_TRIALS,
    *,
    car: CarSpec = DEEPRACER_CAR,
    max_seconds: float = TRIAL_SECONDS,
    seed: int = 0,
    trace: TrialTrace | None = None,
    resets: ResetRules = TRAINING_RESETS,
    on_progress: Callable[[float], None] | None = None,
    race: RaceSettings | None = None,
) -> list[TrialResult]:
    """Drive `trials` one-lap trials from the start line with `driver`, recording every
    step of every trial into `trace` when one is given. `on_progress` hears how far the
    trials have got (0..1) about once per simulated second."""
    if not 1 <= trials <= MAX_TRIALS:
        raise ValueError(f"the number of trials must be between 1 and {MAX_TRIALS}.")
    max_steps = max(1, int(max_seconds * STEP_HZ))
    sim = TrackSimulation(
        track,
        trials,
        car=car,
        rules=EpisodeRules(max_steps=max_steps),
        race=race,
        seed=seed,
    )
    sim.reset_cars(range(trials), [0.0] * trials)
    for index, (offset, yaw_error) in enumerate(start_poses(trials, seed)):
        if index == 0:
            continue
        fleet = sim.fleet
        if sim.objects is None:
            sim.place(index, 0.0, offset)
        else:
            # The start may be in a lane, clear of a box by the line (simapp's start
            # beside an object): the trial's offset is from there, not the centre line.
            yaw = float(fleet.yaw[index])
            x = float(fleet.x[index]) - math.sin(yaw) * offset
            sim.put(index, x, float(fleet.y[index]) + math.cos(yaw) * offset, yaw)
        yaw = float(fleet.yaw[index]) + math.radians(yaw_error)
        sim.put(index, float(fleet.x[index]), float(fleet.y[index]), yaw)
    driver.reset(sim)
    resetter = TrialResets(track, trials, resets)
    length = track.length
    previous = np.zeros(trials)
    seconds = np.full(trials, math.nan)
    status: list[str] = [str(EpisodeStatus.IN_PROGRESS)] * trials
    progress = np.zeros(trials)
    for step in range(max_steps):
        let_other_threads_run(step)  # the app evaluates in a worker thread
        clock = resetter.clock(sim)
        if on_progress is not None and step % PROGRESS_EVERY_STEPS == 0:
            on_progress(_trials_done(seconds, sim.progress, clock, max_seconds))
        for index in np.flatnonzero(np.isnan(seconds) & (clock >= max_seconds - 1e-9)).tolist():
            status[index] = str(EpisodeStatus.TIME_UP)  # its penalties used up its time
            progress[index] = float(sim.progress[index])
            seconds[index] = float(clock[index])
        running = np.isnan(seconds)
        if not running.any():
            break
        resetter.before_step(sim)
        if trace is not None:
            trace.before_step(sim)
        action = driver.act(sim)
        sim.apply(action.steering_deg, action.speed)
        if trace is not None:
            trace.record(sim, np.flatnonzero(running), action.action_index, resetter.penalty)
        travelled = sim.travelled / length * 100.0
        for index in np.flatnonzero(running).tolist():
            state = sim.status[index]
            steps = int(sim.steps[index])
            if state == EpisodeStatus.IN_PROGRESS:
                previous[index] = travelled[index]
                continue
            if resetter.put_back(sim, index, state):  # put back and held: the trial goes on
                previous[index] = float(sim.travelled[index]) / length * 100.0
                continue
            status[index] = str(state)
            progress[index] = float(sim.progress[index])
            if state == EpisodeStatus.LAP_COMPLETE:
                step_gain = max(travelled[index] - previous[index], 1e-9)
                fraction = min(max((100.0 - previous[index]) / step_gain, 0.0), 1.0)
                seconds[index] = (steps - 1 + fraction) * STEP_SECONDS + resetter.penalty[index]
            else:
                seconds[index] = steps * STEP_SECONDS + resetter.penalty[index]
    for index in np.flatnonzero(np.isnan(seconds)).tolist():
        status[index] = str(EpisodeStatus.TIME_UP)
        progress[index] = float(sim.progress[index])
        seconds[index] = float(sim.steps[index]) * STEP_SECONDS + resetter.penalty[index]
    return [
        TrialResult(
            trial=i + 1,
            status=status[i],
            progress=float(progress[i]),
            seconds=seconds[i],
            resets=resetter.resets(i),
            penalty_seconds=float(resetter.penalty[i]),
        )
        for i in range(trials)
    ]


def _trials_done(
    seconds: NDArray[np.float64],
    progress: NDArray[np.float64],
    clock: NDArray[np.float64],
    max_seconds: float,
) -> float:
    """How far a set of trials has got, 0..1: a finished trial counts whole; a running one
    ends at a full lap or at its time limit, whichever comes first, so it counts as the
    larger of the two fractions."""
    running = np.maximum(np.asarray(progress) / 100.0, np.asarray(clock) / max_seconds)
    each = np.where(np.isnan(seconds), np.clip(running, 0.0, 1.0), 1.0)
    return float(each.mean())


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
        # simapp counts every step with one of these statuses: each reset, and the one that
        # ended the trial; reset_count is their sum (`bundle/markov/metrics/s3_metrics.py`).
        for event in (*result.resets, result.status):
            key = _COUNTS.get(EpisodeStatus(event)) if event in _STATUS_SET else None
            if key is not None:
                counts[key] += 1
        counts["reset_count"] = sum(counts.values())
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
    driver: Driver | None = None,
    resets: ResetRules = EVALUATION_RESETS,
    on_progress: Callable[[float], None] | None = None,
) -> EvaluationReport:
    """Evaluate a garage model's policy (or `driver`) and write DRfC's evaluation files:
    `metrics/EvaluationMetrics-<stamp>.json` and its sim-trace,
    `evaluation-<stamp>/evaluation-simtrace/0-iteration.csv`."""
    from sim.training.policy_driver import driver_for_model  # noqa: PLC0415 (torch: only when a model is evaluated)

    chosen = track if track is not None else folder.track()
    trace = TrialTrace()
    results = run_trials(
        driver or driver_for_model(folder),
        chosen,
        trials,
        seed=seed,
        resets=resets,
        trace=trace,
        on_progress=on_progress,
        race=_race_settings(folder),
    )
    rows = evaluation_trials(results)
    stamp = _free_stamp(folder, datetime.now(UTC))
    # The trace first: the metrics file is what says the model was evaluated.
    header = ",".join(SIM_TRACE_COLUMNS) + "\n"
    trace_text = header + sim_trace_lines(trace.columns(rows, chosen.length))
    write_text_atomic(folder.evaluation_trace_file(stamp), trace_text)
    path = folder.evaluation_metrics_file(stamp)
    write_evaluation_metrics(path, rows, physics=CURRENT_PHYSICS)
    return EvaluationReport(track=chosen.name, trials=tuple(results), metrics_file=path)


def _race_settings(folder: ModelFolder) -> RaceSettings | None:
    """A model's boxes or bot cars, evaluated as it trains (None for a time trial)."""

    try:
        settings = race_settings(folder.training_params())
    except (DeepRacerFileError, ModelError):
        return None  # training says what is wrong with it; an evaluation drives a time trial
    return None if settings.race_type is RaceType.TIME_TRIAL else settings


def _free_stamp(folder: ModelFolder, when: datetime) -> str:
    """The evaluation's 14-digit stamp: two evaluations within one second take the next
    free second, since DRfC's names (and deepracer-utils) have room for 14 digits only."""
    while True:
        stamp = evaluation_stamp(when)
        taken = folder.evaluation_metrics_file(stamp).exists()
        if not taken and not folder.evaluation_trace_file(stamp).parent.parent.exists():
            return stamp
        when += timedelta(seconds=1)

"""What a training writes down, as DeepRacer writes it: TrainingMetrics rows and sim-trace.

DeepRacer trains one car and logs every episode and every step of it. racer-tui trains many
cars at once, each a DeepRacer car of its own, so the logbook follows each of them:

- Episodes are numbered in the order they finish, from 1, across all cars; an *iteration*
  is DeepRacer's: `num_episodes_between_training` episodes in a row (the PPO updates
  gather at least that many, from all cars, so they do not line up with iterations).
  `trial` counts the episodes within their iteration, as simapp does, which is how
  deepracer-utils' TrainingMetrics finds the iterations.
- Time is the simulated clock: every step of the fleet adds 1/15 s, so an episode's
  `elapsed_time_in_milliseconds` is its steps at 15 Hz and a sim-trace `tstamp` advances by
  1/15 s per row. A resumed training continues the clock from its last metrics row.
- Every step of every car is kept by a `StepRecorder` (sim.training.step_record) until
  its episode ends; the logbook takes the ended episodes after each step of the fleet
  (`add_step`). As a `StepWatcher` it records a batch in its own process; a training
  spread across processes records in each and hands the episodes over
  (sim.training.shards).

The sim-trace is a sample, because the fleet runs hundreds of times faster than
DeepRacer's one car: whole iterations are traced, every step of every car in them, while
the trace of this run stays within `TRACE_BASE_BYTES` plus `TRACE_BYTES_PER_MINUTE` of
training (iteration 0 always, since deepracer-utils counts episodes per iteration from
it). The counts are kept in TrainingMetrics.json under "sim_trace".

Files are appended: metrics first, then the trace (`flush`), so a killed run never leaves
trace rows for episodes the metrics do not have.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sim.deepracer.files import (
    PREPARE_STATUS,
    TRAINING_METRICS_PATH,
    TRAINING_SIMTRACE_DIR,
    DeepRacerFileError,
    SimTraceColumns,
    SimTraceSample,
    TrainingEpisode,
    TrainingMetrics,
    append_sim_trace,
    append_training_metrics,
    evaluation_stamp,
    sim_trace_lines,
    trace_status,
    training_metrics_end,
    training_trace_path,
)
from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.car import STEP_SECONDS
from sim.physics.objects.seen import SeenObjects, write_seen
from sim.physics.simulation import TrackSimulation
from sim.training.step_record import (
    ACTION,
    PROGRESS,
    REWARD,
    SEGMENT,
    STEER,
    THROTTLE,
    WHEELS,
    YAW,
    EndedEpisode,
    StepRecorder,
    X,
    Y,
)

TRACE_BASE_BYTES = 10_000_000
TRACE_BYTES_PER_MINUTE = 1_000_000
TRACE_RULE = (
    "every step of every car in whole iterations, iteration 0 always, while a run's trace "
    "stays within 10 MB plus 1 MB per minute of training"
)
_BYTES_PER_ROW = 110  # about what one row takes on disk, to budget before formatting
# A traced episode waiting to be written: (episode column, clock at its end, status, rows).
_TracedEpisode = tuple[int, float, str, NDArray[np.float64]]


@dataclass(frozen=True)
class FinishedEpisode:
    """One finished training episode: the logbook numbers it as the metrics do; a PPO
    rollout, which only counts and averages its episodes, leaves `number` at 0."""

    car: int
    reward: float
    progress: float
    status: str
    steps: int
    number: int = 0  # from 1, in the order episodes finish (0: not numbered)

    @property
    def lap_time(self) -> float | None:
        """A completed lap's time: its steps at 15 Hz (the prepare step included)."""
        if self.status == EpisodeStatus.LAP_COMPLETE:
            return self.steps * STEP_SECONDS
        return None


class Logbook:
    """Training metrics and sim-trace of one training run of one model folder."""

    def __init__(
        self,
        folder: Path,
        *,
        cars: int,
        episodes_per_iteration: int,
        track_length: float,
        waypoints: NDArray[np.float64],
        discrete: bool,
        clock: Callable[[], float] = time.monotonic,
        trace_base_bytes: int = TRACE_BASE_BYTES,
        trace_bytes_per_minute: int = TRACE_BYTES_PER_MINUTE,
    ) -> None:
        self.metrics_file = folder / TRAINING_METRICS_PATH
        self.folder = folder
        self.cars = cars
        self.per_iteration = max(1, episodes_per_iteration)
        self.track_length = float(track_length)
        self._waypoints = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
        self._discrete = discrete
        self._now = clock
        self._started = clock()
        self._trace_base = trace_base_bytes
        self._trace_rate = trace_bytes_per_minute
        self._recorder = StepRecorder(cars, discrete=discrete)
        self._pending_metrics: list[TrainingEpisode] = []
        self._pending_trace: dict[int, list[_TracedEpisode]] = {}
        self._traced_iterations: dict[int, bool] = {}
        self._run_trace_bytes = 0
        # The objects at the end of the last traced episode (sim.physics.objects.seen).
        self._seen: SeenObjects | None = None
        self.finished: list[FinishedEpisode] = []  # since the trainer last took them
        self.episodes = 0
        self.clock = 0.0  # simulated seconds
        self.sample = SimTraceSample(0, 0, 0, TRACE_RULE)
        self._resume()

    # --- where a resumed training continues ----------------------------------------------------
    def _resume(self) -> None:
        try:
            last, sample = training_metrics_end(self.metrics_file)
        except DeepRacerFileError:
            # Unreadable old metrics: kept beside under another name, and a new log starts.
            stamp = evaluation_stamp()
            self.metrics_file.rename(self.metrics_file.with_name(f"unreadable-{stamp}.json"))
            last, sample = None, None
        if last is not None:
            self.episodes = last.episode
            self.clock = last.metric_time / 1000.0
        if sample is not None:
            self.sample = SimTraceSample(
                self.episodes, sample.traced_episodes, sample.traced_steps, TRACE_RULE
            )
        else:
            self.sample = SimTraceSample(self.episodes, 0, 0, TRACE_RULE)
        self._trim_cut_lines()

    def _trim_cut_lines(self) -> None:
        """A run killed while appending may leave a last trace line cut short: drop it."""
        traces = sorted(
            (self.folder / TRAINING_SIMTRACE_DIR).glob("*-iteration.csv"),
            key=lambda path: int(path.name.split("-")[0]) if path.name[0].isdigit() else -1,
        )
        for path in traces[-2:]:
            data = path.read_bytes()
            if data and not data.endswith(b"\n"):
                with path.open("r+b") as handle:
                    handle.truncate(data.rfind(b"\n") + 1)

    # --- every step ----------------------------------------------------------------------------
    def before_step(self, sim: TrackSimulation) -> None:
        """Note where every car is before the fleet's step (a row's pose is one row late)."""
        self._recorder.before_step(sim)

    def after_step(self, sim: TrackSimulation, actions: np.ndarray, rewards: np.ndarray) -> None:
        """Record the fleet's step; called by the env before finished cars restart."""
        self._recorder.after_step(sim, actions, rewards)
        self.add_step(self._recorder.take())

    def add_step(self, ended: list[EndedEpisode]) -> None:
        """One step of the whole fleet, and the episodes it ended, in the cars' order."""
        self.clock += STEP_SECONDS
        for episode in ended:
            self._finish(episode)

    def _finish(self, ended: EndedEpisode) -> None:
        self.episodes += 1
        number = self.episodes
        rows, steps, status = ended.rows, ended.steps, ended.status
        reward = float(rows[:, REWARD].sum())
        progress = float(rows[-1, PROGRESS])
        end, elapsed = round(self.clock * 1000), round(steps * STEP_SECONDS * 1000)
        self._pending_metrics.append(
            TrainingEpisode(
                reward_score=round(reward, 4),
                metric_time=end,
                start_time=end - elapsed,
                elapsed_time_in_milliseconds=elapsed,
                episode=number,
                trial=self.trial(number),
                phase="training",
                completion_percentage=round(progress, 2),
                episode_status=status,
            )
        )
        self.finished.append(FinishedEpisode(ended.car, reward, progress, status, steps, number))
        iteration = (number - 1) // self.per_iteration
        if self._traced(iteration):
            self._pending_trace.setdefault(iteration, []).append(
                (number - 1, self.clock, status, rows)
            )
            self._run_trace_bytes += steps * _BYTES_PER_ROW
            if ended.objects is not None:  # where they stood at this, the last traced row
                self._seen = SeenObjects(number - 1, steps, ended.objects_are_cars, ended.objects)
            self.sample = SimTraceSample(
                number,
                self.sample.traced_episodes + 1,
                self.sample.traced_steps + steps,
                TRACE_RULE,
            )
        else:
            self.sample = SimTraceSample(
                number, self.sample.traced_episodes, self.sample.traced_steps, TRACE_RULE
            )

    def trial(self, episode: int) -> int:
        """simapp's `trial`: training episodes so far in the current iteration."""
        return (episode - 1) % self.per_iteration + 1 if episode > 0 else 0

    def _traced(self, iteration: int) -> bool:
        decided = self._traced_iterations.get(iteration)
        if decided is None:
            minutes = (self._now() - self._started) / 60.0
            budget = self._trace_base + self._trace_rate * minutes
            decided = iteration == 0 or self._run_trace_bytes <= budget
            self._traced_iterations = {iteration: decided}  # iterations finish in order
        return decided

    # --- evaluations during training --------------------------------------------------------
    def add_evaluation(self, trials: list[tuple[float, float, str]]) -> None:
        """Evaluation episodes (seconds, progress, status), back to back from the clock, as
        simapp logs the evaluations between iterations: `episode` and `trial` stay those of
        the last training episode."""
        start = round(self.clock * 1000)
        for seconds, progress, status in trials:
            elapsed = round(seconds * 1000)
            self._pending_metrics.append(
                TrainingEpisode(
                    reward_score=0,
                    metric_time=start + elapsed,
                    start_time=start,
                    elapsed_time_in_milliseconds=elapsed,
                    episode=self.episodes,
                    trial=self.trial(self.episodes),
                    phase="evaluation",
                    completion_percentage=round(progress, 2),
                    episode_status=status,
                )
            )
            start += elapsed

    # --- writing --------------------------------------------------------------------------------
    @property
    def pending(self) -> bool:
        return bool(self._pending_metrics or self._pending_trace)

    def flush(self) -> None:
        """Append what finished since the last flush: metrics, then sim-trace."""
        if self._pending_metrics:
            template = TrainingMetrics((), sim_trace=self.sample)
            append_training_metrics(self.metrics_file, self._pending_metrics, template)
            self._pending_metrics = []
        for iteration, episodes in sorted(self._pending_trace.items()):
            append_sim_trace(
                self.folder / training_trace_path(iteration),
                sim_trace_lines(self._columns(episodes)),
            )
        self._pending_trace = {}
        if self._seen is not None:
            write_seen(self.folder, self._seen)
            self._seen = None

    def _columns(self, episodes: list[_TracedEpisode]) -> SimTraceColumns:
        numbers, steps, stamps, statuses, blocks = [], [], [], [], []
        for episode, clock, status, rows in episodes:
            count = len(rows)
            index = np.arange(count)
            numbers.append(np.full(count, episode))
            steps.append(index + 1)
            # The row of step k ended (count - k) steps before the episode's last one.
            stamps.append(clock - (count - 1 - index) * STEP_SECONDS)
            statuses.extend(_row_statuses(count, status))
            blocks.append(rows)
        data = np.concatenate(blocks)
        step = np.concatenate(steps)
        ends = np.cumsum([len(rows) for rows in blocks]) - 1
        done = np.zeros(len(step), dtype=bool)
        done[ends] = True
        return SimTraceColumns(
            episode=np.concatenate(numbers),
            steps=step,
            x=data[:, X],
            y=data[:, Y],
            yaw=data[:, YAW],
            steer=data[:, STEER],
            throttle=data[:, THROTTLE],
            action=data[:, ACTION].astype(np.int64),
            reward=data[:, REWARD],
            done=done,
            all_wheels_on_track=data[:, WHEELS] > 0.5,
            progress=data[:, PROGRESS],
            closest_waypoint=closest_waypoint(
                data[:, X : Y + 1], data[:, SEGMENT].astype(np.int64), self._waypoints
            ),
            track_len=self.track_length,
            tstamp=np.concatenate(stamps),
            episode_status=statuses,
        )

    def take_finished(self) -> list[FinishedEpisode]:
        finished, self.finished = self.finished, []
        return finished


def closest_waypoint(
    points: NDArray[np.float64], segments: NDArray[np.int64], waypoints: NDArray[np.float64]
) -> NDArray[np.int64]:
    """simapp's sim-trace `closest_waypoint`: the nearer end of the centre-line segment
    each point is on."""
    count = len(waypoints)
    before = np.asarray(segments, dtype=np.int64) % count
    after = (before + 1) % count
    to_before = np.hypot(*(points - waypoints[before]).T)
    to_after = np.hypot(*(points - waypoints[after]).T)
    return np.where(to_after < to_before, after, before)


def _row_statuses(count: int, final: str) -> list[str]:
    """simapp's row statuses: the first step prepares, the last one says how it ended."""
    statuses = [trace_status(EpisodeStatus.IN_PROGRESS)] * count
    if count > 1:
        statuses[0] = PREPARE_STATUS
    statuses[-1] = trace_status(final)
    return statuses

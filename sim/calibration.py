"""Replaying DeepRacer's sim-traces through racer-tui's car: the figures that calibrate it.

Facts of DeepRacer's sim-trace this relies on (deepracer-simapp's `set_reward_and_metrics`,
checked on the console's and DeepRacer-on-AWS traces):
- `X`, `Y` are the point `LOOK_AHEAD` (0.14 m) ahead of the car's origin along its heading
  (the reward's `x`, `y`), `yaw` is the heading in degrees; the car's origin is midway
  between its axles, racer-tui's car centre.
- A row's pose is one row late: the pose of row i+1 is the car's state at row i's `tstamp`,
  when row i's command starts to act. The distance between rows i and i+1 follows the time
  step of the row before (t[i] - t[i-1]) far better than its own, in every trace looked at.
  So each row's command pairs with the *next* row's pose, and acts until the row after.

The replay (`calibrate`) drives racer-tui's car with a trace's commands, open-loop:
- one long replay per stretch of driving gives racer-tui's curvature, yaw response and
  speed for the same command history as DeepRacer's, compared interval by interval;
- windows of 2 s, one starting at every pose, start from the trace's pose, speed and the
  long replay's wheel angle, and give the position gap after 1 s and 2 s.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sim.deepracer.files import SimTraceRow
from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec, Fleet
from sim.physics.simulation import LOOK_AHEAD

CURVATURE_TOLERANCE = 0.10  # racer-tui's curvature within 10 % of DeepRacer's, every bin
GAP_TARGETS = {1.0: 0.2, 2.0: 0.5}  # seconds after the start -> median gap, metres

_DRIVING = "in_progress"
_LAST_POSES = ("lap_complete", "off_track")  # the pose is real; the car is moved after it
_MIN_STEP, _MAX_STEP = 0.03, 0.15  # a row's time step, seconds: longer is a pause
_MAX_JUMP = 0.6  # metres between poses: more is a reset, not driving
_SETTLE = 8  # poses into a run before it is compared: the start's wheel angle is a guess
_HELD = 3  # intervals a command must be held for its curvature and speed to count
_HELD_TOLERANCE = 1.0  # degrees, m/s x 0.1: "the same command" for continuous actions
_MIN_ARC = 0.02  # metres: shorter intervals give no usable curvature
_MIN_BIN_SAMPLES = 10
_LAG_TAPS = 20  # impulse-response length for the lag, steps (1.3 s)
_WINDOW_BATCH = 512


@dataclass(frozen=True)
class Run:
    """Consecutive poses of one episode, each with the command that starts acting then."""

    time: FloatArray  # (n,) seconds: when the car had this pose
    x: FloatArray  # car centre, metres
    y: FloatArray
    yaw: FloatArray  # radians, unwrapped
    steering: FloatArray  # degrees, the command from this pose to the next
    speed: FloatArray  # m/s, commanded

    def __len__(self) -> int:
        return len(self.time)

    @property
    def arc(self) -> FloatArray:
        """Distance driven by the car centre since the first pose."""
        return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(self.x), np.diff(self.y)))])

    def speed_at_poses(self) -> FloatArray:
        """The trace's speed at each pose (central differences of the centre's path)."""
        return np.gradient(self.arc, self.time)


def trace_runs(rows: Sequence[SimTraceRow], min_poses: int = _SETTLE + 4) -> list[Run]:
    """Split a sim-trace into runs of driving, pairing each row's command with the next
    row's pose (see the module docstring); pauses, resets and 'prepare' steps end a run."""
    runs: list[Run] = []
    current: list[tuple[float, float, float, float, float, float]] = []

    def close() -> None:
        if len(current) >= min_poses:
            columns = np.array(current).T
            yaw = np.unwrap(np.radians(columns[3]))
            x = columns[1] - LOOK_AHEAD * np.cos(yaw)
            y = columns[2] - LOOK_AHEAD * np.sin(yaw)
            runs.append(Run(columns[0], x, y, yaw, columns[4], columns[5]))
        current.clear()

    for command, pose in itertools.pairwise(rows):
        paired = (
            pose.episode == command.episode
            and pose.steps == command.steps + 1
            and command.episode_status == _DRIVING
            and pose.episode_status in (_DRIVING, *_LAST_POSES)
            and command.pause_duration == 0.0
        )
        if paired and current:
            last = current[-1]
            step = command.tstamp - last[0]
            jump = math.hypot(pose.x - last[1], pose.y - last[2])
            paired = _MIN_STEP < step < _MAX_STEP and jump < _MAX_JUMP
        if not paired:
            close()
            continue
        current.append((command.tstamp, pose.x, pose.y, pose.yaw, command.steer, command.throttle))
        if pose.episode_status in _LAST_POSES:
            close()
    close()
    return runs


class _Commands:
    """Each run's commands by time, for looking up many runs at once."""

    def __init__(self, runs: Sequence[Run]) -> None:
        longest = max(len(run) for run in runs)
        self._time = np.full((len(runs), longest), np.inf)
        self._steering = np.zeros((len(runs), longest))
        self._speed = np.zeros((len(runs), longest))
        for i, run in enumerate(runs):
            self._time[i, : len(run)] = run.time
            self._steering[i, : len(run)] = run.steering
            self._speed[i, : len(run)] = run.speed
        self._rows = np.arange(len(runs))

    def at(
        self, times: FloatArray, rows: np.ndarray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """The command (steering degrees, speed) acting at `times[i]` in run `rows[i]`
        (every run when `rows` is None): the last one sent at or before it; before a run's
        first pose, its first command. Asked at a sub-step's middle, this starts each
        command on the sub-step nearest its time."""
        rows = self._rows if rows is None else rows
        sent = np.count_nonzero(self._time[rows] <= times[:, None], axis=1)
        k = np.maximum(sent - 1, 0)
        return self._steering[rows, k], self._speed[rows, k]


def _substeps_until(seconds: float, car: Fleet) -> int:
    return math.ceil(seconds / car.dt - 1e-9)


@dataclass(frozen=True)
class _Replayed:
    """racer-tui's car driven through one run, sampled at the run's pose times."""

    yaw: FloatArray
    arc: FloatArray
    steering: FloatArray  # radians, the wheel angle


def replay_runs(runs: Sequence[Run], car: CarSpec) -> list[_Replayed]:
    """Drive one car per run with the run's commands, open-loop, from its first pose."""
    fleet = Fleet(len(runs), car)
    for i, run in enumerate(runs):
        start_speed = float(run.speed_at_poses()[0])
        fleet.place(
            i,
            float(run.x[0]),
            float(run.y[0]),
            float(run.yaw[0]),
            start_speed,
            steering=math.radians(float(run.steering[0])),
        )
    starts = np.array([run.time[0] for run in runs])
    duration = max(float(run.time[-1] - run.time[0]) for run in runs)
    # DeepRacer sends its commands at irregular times (its steps jitter around 1/15 s):
    # each one is applied from its own time, to the nearest physics sub-step, not on a 15 Hz
    # grid that would start it up to a whole step late.
    substeps = _substeps_until(duration, fleet) + 1
    commands = _Commands(runs)
    x, y, yaw, steering = (np.empty((substeps + 1, len(runs))) for _ in range(4))
    x[0], y[0], yaw[0], steering[0] = fleet.x, fleet.y, fleet.yaw, fleet.steering
    for m in range(substeps):
        fleet.set_targets(*commands.at(starts + (m + 0.5) * fleet.dt))
        fleet.advance(1)
        x[m + 1], y[m + 1], yaw[m + 1], steering[m + 1] = (
            fleet.x,
            fleet.y,
            fleet.yaw,
            fleet.steering,
        )
    grid = np.arange(substeps + 1) * fleet.dt
    arc = np.concatenate(
        [
            np.zeros((1, len(runs))),
            np.cumsum(np.hypot(np.diff(x, axis=0), np.diff(y, axis=0)), axis=0),
        ]
    )
    replayed = []
    for i, run in enumerate(runs):
        at = run.time - starts[i]
        replayed.append(
            _Replayed(
                yaw=np.interp(at, grid, yaw[:, i]),
                arc=np.interp(at, grid, arc[:, i]),
                steering=np.interp(at, grid, steering[:, i]),
            )
        )
    return replayed


@dataclass(frozen=True)
class _Intervals:
    """Every compared interval between two poses, DeepRacer's and racer-tui's side by side."""

    run: np.ndarray  # (n,) index of the run
    index: np.ndarray  # (n,) pose index within the run where the interval starts
    steering: FloatArray  # degrees, the command acting
    speed_command: FloatArray
    held: np.ndarray  # bool: that command held for `_HELD` intervals
    curvature: FloatArray  # DeepRacer's, 1/m
    racer_curvature: FloatArray
    speed: FloatArray  # DeepRacer's, m/s
    racer_speed: FloatArray


def _intervals(runs: Sequence[Run], replayed: Sequence[_Replayed]) -> _Intervals:
    parts: dict[str, list[np.ndarray]] = {}
    for r, (run, sim) in enumerate(zip(runs, replayed, strict=True)):
        k = np.arange(_SETTLE, len(run) - 1)
        dt = np.diff(run.time)[k]
        arc = np.diff(run.arc)[k]
        racer_arc = np.diff(sim.arc)[k]
        held = np.ones(len(k), dtype=bool)
        for back in range(1, _HELD):
            held &= np.abs(run.steering[k - back] - run.steering[k]) <= _HELD_TOLERANCE
            held &= np.abs(run.speed[k - back] - run.speed[k]) <= 0.1 * _HELD_TOLERANCE
        keep = (arc >= _MIN_ARC) & (racer_arc >= _MIN_ARC)
        columns = {
            "run": np.full(len(k), r),
            "index": k,
            "steering": run.steering[k],
            "speed_command": run.speed[k],
            "held": held,
            "curvature": np.diff(run.yaw)[k] / np.maximum(arc, 1e-9),
            "racer_curvature": np.diff(sim.yaw)[k] / np.maximum(racer_arc, 1e-9),
            "speed": arc / dt,
            "racer_speed": racer_arc / dt,
        }
        for name, values in columns.items():
            parts.setdefault(name, []).append(values[keep])
    joined = {name: np.concatenate(values) for name, values in parts.items()}
    return _Intervals(**joined)


@dataclass(frozen=True)
class CurvatureBin:
    """Steady-steering curvature in one steering-angle and speed bin."""

    steering_deg: int  # |steering| rounded to 5 degrees
    speed: int  # m/s, rounded
    samples: int
    deepracer: float  # mean path curvature, 1/m, towards the command's side
    racer_tui: float

    @property
    def ratio(self) -> float:
        return self.racer_tui / self.deepracer


def _curvature_bins(intervals: _Intervals) -> list[CurvatureBin]:
    steering_bin = (np.round(np.abs(intervals.steering) / 5.0) * 5.0).astype(int)
    speed_bin = np.round(intervals.speed).astype(int)
    side = np.sign(intervals.steering)
    bins = []
    for angle in sorted(set(steering_bin[steering_bin > 0].tolist())):
        for speed in sorted(set(speed_bin.tolist())):
            chosen = intervals.held & (steering_bin == angle) & (speed_bin == speed)
            if speed < 1 or chosen.sum() < _MIN_BIN_SAMPLES:
                continue
            # Means, not medians: the held commands' curvatures still carry the transients
            # of what came before, and a mean of a linear response compares like for like.
            deepracer = float(np.mean(side[chosen] * intervals.curvature[chosen]))
            racer = float(np.mean(side[chosen] * intervals.racer_curvature[chosen]))
            bins.append(CurvatureBin(angle, speed, int(chosen.sum()), deepracer, racer))
    return bins


def _lag(intervals: _Intervals, runs: Sequence[Run], curvature: FloatArray) -> float:
    """Seconds until the curvature reaches 63 % of its answer to a steering step.

    The step response comes from an impulse response fitted by least squares to every
    interval (the curvature against the last `_LAG_TAPS` commands' tan(angle)), so it
    needs no clean steps in the trace and measures DeepRacer and racer-tui alike.
    """
    usable = intervals.index >= _LAG_TAPS - 1
    regressors = np.empty((int(usable.sum()), _LAG_TAPS))
    steps: list[float] = []
    for row, (r, k) in enumerate(zip(intervals.run[usable], intervals.index[usable], strict=True)):
        run = runs[int(r)]
        regressors[row] = np.tan(np.radians(run.steering[k - np.arange(_LAG_TAPS)]))
        steps.append(float(run.time[k + 1] - run.time[k]))
    if len(regressors) < 4 * _LAG_TAPS:
        return math.nan
    impulse, *_ = np.linalg.lstsq(regressors, curvature[usable], rcond=None)
    response = np.concatenate([[0.0], np.cumsum(impulse) / np.sum(impulse)])
    step = float(np.mean(steps))
    reached = int(np.argmax(response >= 1.0 - math.exp(-1.0)))
    if reached == 0:
        return math.nan
    before, after = response[reached - 1], response[reached]
    fraction = (1.0 - math.exp(-1.0) - before) / (after - before)
    return float((reached - 1 + fraction) * step)


def _window_gaps(
    runs: Sequence[Run], replayed: Sequence[_Replayed], car: CarSpec
) -> dict[float, FloatArray]:
    """Position gaps of the reported point after each of `GAP_TARGETS`' times, one window
    per starting pose: start from the trace's pose and speed, replay its commands."""
    horizon = max(GAP_TARGETS)
    starts = [
        (r, k)
        for r, run in enumerate(runs)
        for k in range(_SETTLE, len(run))
        if run.time[k] + horizon <= run.time[-1]
    ]
    gaps: dict[float, list[float]] = {at: [] for at in GAP_TARGETS}
    commands = _Commands(runs)
    for first in range(0, len(starts), _WINDOW_BATCH):
        batch = starts[first : first + _WINDOW_BATCH]
        rows = np.array([r for r, _ in batch])
        fleet = Fleet(len(batch), car)
        begin = np.empty(len(batch))
        for i, (r, k) in enumerate(batch):
            run = runs[r]
            fleet.place(
                i,
                float(run.x[k]),
                float(run.y[k]),
                float(run.yaw[k]),
                float(run.speed_at_poses()[k]),
                steering=float(replayed[r].steering[k]),
            )
            begin[i] = run.time[k]
        done = 0
        for at in sorted(GAP_TARGETS):
            for m in range(done, _substeps_until(at, fleet)):
                fleet.set_targets(*commands.at(begin + (m + 0.5) * fleet.dt, rows))
                fleet.advance(1)
            done = _substeps_until(at, fleet)
            ahead = fleet.points_ahead(LOOK_AHEAD)
            for i, (r, _) in enumerate(batch):
                run = runs[r]
                when = begin[i] + done * fleet.dt
                tx = np.interp(when, run.time, run.x + LOOK_AHEAD * np.cos(run.yaw))
                ty = np.interp(when, run.time, run.y + LOOK_AHEAD * np.sin(run.yaw))
                gaps[at].append(math.hypot(ahead[i, 0] - tx, ahead[i, 1] - ty))
    return {at: np.array(values) for at, values in gaps.items()}


@dataclass(frozen=True)
class Calibration:
    """How racer-tui's car follows a DeepRacer trace's commands."""

    runs: int
    intervals: int
    windows: int
    curvature: list[CurvatureBin]
    lag_deepracer: float  # seconds to 63 % of a steering step's curvature
    lag_racer_tui: float
    speed_ratio_deepracer: float  # reached over commanded speed, commands held
    speed_ratio_racer_tui: float
    gaps: dict[float, float]  # median position gap of the reported point after 1 s, 2 s

    @property
    def curvature_within_tolerance(self) -> bool:
        return bool(self.curvature) and all(
            abs(b.ratio - 1.0) <= CURVATURE_TOLERANCE for b in self.curvature
        )

    @property
    def gaps_within_targets(self) -> bool:
        return all(self.gaps[at] < target for at, target in GAP_TARGETS.items())

    @property
    def meets_targets(self) -> bool:
        return self.curvature_within_tolerance and self.gaps_within_targets


def calibrate(traces: Sequence[Sequence[SimTraceRow]], car: CarSpec) -> Calibration:
    """Replay DeepRacer sim-traces' commands through `car` and compare (module docstring).
    Each trace is one file's rows; their runs are pooled."""
    runs = [run for rows in traces for run in trace_runs(rows)]
    if not runs:
        raise ValueError("the trace holds no stretch of driving long enough to replay")
    replayed = replay_runs(runs, car)
    intervals = _intervals(runs, replayed)
    held = intervals.held
    gaps = _window_gaps(runs, replayed, car)
    return Calibration(
        runs=len(runs),
        intervals=len(intervals.steering),
        windows=len(gaps[max(GAP_TARGETS)]),
        curvature=_curvature_bins(intervals),
        lag_deepracer=_lag(intervals, runs, intervals.curvature),
        lag_racer_tui=_lag(intervals, runs, intervals.racer_curvature),
        speed_ratio_deepracer=float(
            np.median(intervals.speed[held] / intervals.speed_command[held])
        ),
        speed_ratio_racer_tui=float(
            np.median(intervals.racer_speed[held] / intervals.speed_command[held])
        ),
        gaps={at: float(np.median(values)) for at, values in gaps.items()},
    )

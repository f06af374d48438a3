"""A race's step-by-step trace: compact numpy columns, written as a DeepRacer sim-trace CSV.

One row per race tick (a 1/15 s physics step, or a tick of a penalty hold), plus a first
"prepare" row with the car on the start line at t = 0. A viewer replays it; a ghost
comparison reads two of them side by side.

Sim-trace mapping (columns as DeepRacer writes them, via `sim.deepracer.files`):
episode = lap number - 1 (the lap in progress), steps = row number from 1, X/Y = car centre,
yaw = heading in degrees, steer/throttle = the commanded action, action = its index (-1 for
continuous spaces and for rows where nothing drove), reward = 0 (a race has no reward),
done = True on the last row, progress = percent of the current lap, closest_waypoint = the
centre-line point behind the car, tstamp = race clock, episode_status = what happened on
that row ("pause" while held after an off-track), pause_duration = the penalty seconds that
row's off-track or crash starts (0 elsewhere), so the column sums to the penalty time.
The car's real speed is not a sim-trace column: reading a CSV back derives it from the
distance moved between rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np
from numpy.typing import NDArray

from sim.deepracer.files import (
    PREPARE_STATUS,
    SimTraceRow,
    read_sim_trace,
    trace_status,
    write_sim_trace,
)
from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.remedies import RemedyError

PAUSE_STATUS: Final = "pause"
# Row statuses in sim-trace spelling; the trace stores each as its index here.
TRACE_STATUSES: Final[tuple[str, ...]] = (
    PREPARE_STATUS,
    trace_status(EpisodeStatus.IN_PROGRESS),
    trace_status(EpisodeStatus.OFF_TRACK),
    PAUSE_STATUS,
    trace_status(EpisodeStatus.LAP_COMPLETE),
    trace_status(EpisodeStatus.REVERSED),
    trace_status(EpisodeStatus.CRASHED),
    trace_status(EpisodeStatus.TIME_UP),
)
STATUS_CODE: Final[dict[str, int]] = {name: code for code, name in enumerate(TRACE_STATUSES)}
# The codes the race engines write (`sim.race.engine`, `sim.race.head_to_head`).
PREPARE: Final = STATUS_CODE[PREPARE_STATUS]
IN_PROGRESS: Final = STATUS_CODE["in_progress"]
OFF_TRACK: Final = STATUS_CODE["off_track"]
PAUSE: Final = STATUS_CODE[PAUSE_STATUS]
LAP_COMPLETE: Final = STATUS_CODE["lap_complete"]
REVERSED: Final = STATUS_CODE["reversed"]
CRASHED: Final = STATUS_CODE["crashed"]
TIME_UP: Final = STATUS_CODE["time_up"]


class TraceError(RemedyError):
    """A sim-trace file that cannot be replayed as a race; the message says why."""


@dataclass(frozen=True, eq=False)
class RaceTrace:
    """Per-row columns of a race (all the same length)."""

    t: NDArray[np.float64]  # race clock, seconds
    x: NDArray[np.float32]  # car centre, metres
    y: NDArray[np.float32]
    heading: NDArray[np.float32]  # degrees, (-180, 180], 0 = +x, counter-clockwise positive
    speed: NDArray[np.float32]  # the car's real speed, m/s
    steering: NDArray[np.float32]  # commanded steering, degrees
    throttle: NDArray[np.float32]  # commanded speed, m/s
    action: NDArray[np.int16]  # discrete action index, -1 when continuous or nothing drove
    status: NDArray[np.uint8]  # index into TRACE_STATUSES
    lap: NDArray[np.int16]  # lap number in progress (1-based)
    offtrack: NDArray[np.bool_]  # all four wheels off the road on this row
    all_wheels_on: NDArray[np.bool_]
    progress: NDArray[np.float32]  # percent of the current lap
    waypoint: NDArray[np.int32]  # closest centre-line point behind the car
    pause: NDArray[np.float32]  # penalty seconds started on this row
    track_length: float = 0.0

    def __len__(self) -> int:
        return len(self.t)

    def statuses(self) -> list[str]:
        return [TRACE_STATUSES[code] for code in self.status.tolist()]

    def to_sim_trace_rows(self) -> list[SimTraceRow]:
        last = len(self) - 1
        columns = zip(
            self.t.tolist(),
            self.x.tolist(),
            self.y.tolist(),
            self.heading.tolist(),
            self.steering.tolist(),
            self.throttle.tolist(),
            self.action.tolist(),
            self.status.tolist(),
            self.lap.tolist(),
            self.all_wheels_on.tolist(),
            self.progress.tolist(),
            self.waypoint.tolist(),
            self.pause.tolist(),
            strict=True,
        )
        return [
            SimTraceRow(
                episode=lap - 1,
                steps=row + 1,
                x=x,
                y=y,
                yaw=heading,
                steer=steer,
                throttle=throttle,
                action=action,
                reward=0.0,
                done=row == last,
                all_wheels_on_track=wheels_on,
                progress=progress,
                closest_waypoint=waypoint,
                track_len=self.track_length,
                tstamp=t,
                episode_status=TRACE_STATUSES[status],
                pause_duration=pause,
            )
            for row, (
                t,
                x,
                y,
                heading,
                steer,
                throttle,
                action,
                status,
                lap,
                wheels_on,
                progress,
                waypoint,
                pause,
            ) in enumerate(columns)
        ]

    def write_csv(self, path: Path) -> None:
        """Write as a DeepRacer sim-trace CSV (atomically)."""
        write_sim_trace(path, self.to_sim_trace_rows())

    @classmethod
    def from_sim_trace_rows(cls, rows: Sequence[SimTraceRow]) -> RaceTrace:
        """Rebuild a trace from sim-trace rows (ours, or a DeepRacer evaluation's)."""
        if not rows:
            raise TraceError("the sim-trace has no rows; record the race again.")
        t = np.array([row.tstamp for row in rows], dtype=np.float64)
        if np.any(np.diff(t) < 0.0):
            raise TraceError("the sim-trace's tstamp column goes backwards; it is not one race.")
        x = np.array([row.x for row in rows], dtype=np.float64)
        y = np.array([row.y for row in rows], dtype=np.float64)
        dt = np.diff(t)
        moved = np.hypot(np.diff(x), np.diff(y))
        speed = np.zeros(len(rows))
        speed[1:] = np.where(dt > 0.0, moved / np.where(dt > 0.0, dt, 1.0), 0.0)
        unknown = STATUS_CODE[trace_status(EpisodeStatus.IN_PROGRESS)]
        return cls(
            t=t,
            x=x.astype(np.float32),
            y=y.astype(np.float32),
            heading=np.array([row.yaw for row in rows], dtype=np.float32),
            speed=speed.astype(np.float32),
            steering=np.array([row.steer for row in rows], dtype=np.float32),
            throttle=np.array([row.throttle for row in rows], dtype=np.float32),
            action=np.clip([row.action for row in rows], -1, 32767).astype(np.int16),
            status=np.array(
                [STATUS_CODE.get(row.episode_status, unknown) for row in rows], dtype=np.uint8
            ),
            lap=np.clip([row.episode + 1 for row in rows], 1, 32767).astype(np.int16),
            offtrack=np.array(
                [row.episode_status == TRACE_STATUSES[2] for row in rows], dtype=np.bool_
            ),
            all_wheels_on=np.array([row.all_wheels_on_track for row in rows], dtype=np.bool_),
            progress=np.array([row.progress for row in rows], dtype=np.float32),
            waypoint=np.array([row.closest_waypoint for row in rows], dtype=np.int32),
            pause=np.array([row.pause_duration for row in rows], dtype=np.float32),
            track_length=rows[0].track_len,
        )

    @classmethod
    def read_csv(cls, path: Path) -> RaceTrace:
        """Read a sim-trace CSV back (raises DeepRacerFileError / TraceError on bad files)."""
        return cls.from_sim_trace_rows(read_sim_trace(path))


class TraceRecorder:
    """Fills preallocated columns one row at a time; `finish` trims them into a RaceTrace."""

    def __init__(self, capacity: int, track_length: float) -> None:
        self._n = 0
        self._capacity = max(capacity, 1)
        self._track_length = track_length
        self._allocate(self._capacity)

    def _allocate(self, capacity: int) -> None:
        self._t = np.zeros(capacity, dtype=np.float64)
        # x, y, heading, speed, steering, throttle, progress, pause
        self._f32 = np.zeros((capacity, 8), dtype=np.float32)
        self._action = np.zeros(capacity, dtype=np.int16)
        self._status = np.zeros(capacity, dtype=np.uint8)
        self._lap = np.zeros(capacity, dtype=np.int16)
        self._flags = np.zeros((capacity, 2), dtype=np.bool_)
        self._waypoint = np.zeros(capacity, dtype=np.int32)

    def _grow(self) -> None:
        n = self._n
        old_t, old_f32, old_action = self._t, self._f32, self._action
        old_status, old_lap, old_flags, old_waypoint = (
            self._status,
            self._lap,
            self._flags,
            self._waypoint,
        )
        self._capacity *= 2
        self._allocate(self._capacity)
        self._t[:n] = old_t[:n]
        self._f32[:n] = old_f32[:n]
        self._action[:n] = old_action[:n]
        self._status[:n] = old_status[:n]
        self._lap[:n] = old_lap[:n]
        self._flags[:n] = old_flags[:n]
        self._waypoint[:n] = old_waypoint[:n]

    def add(
        self,
        *,
        t: float,
        x: float,
        y: float,
        heading: float,
        speed: float,
        steering: float,
        throttle: float,
        action: int,
        status: int,
        lap: int,
        offtrack: bool,
        all_wheels_on: bool,
        progress: float,
        waypoint: int,
        pause: float = 0.0,
    ) -> None:
        if self._n == self._capacity:
            self._grow()
        i = self._n
        self._t[i] = t
        self._f32[i] = (x, y, heading, speed, steering, throttle, progress, pause)
        self._action[i] = action
        self._status[i] = status
        self._lap[i] = lap
        self._flags[i] = (offtrack, all_wheels_on)
        self._waypoint[i] = waypoint
        self._n = i + 1

    def finish_race(self) -> RaceTrace:
        """The trace of a race that has ended: a last row with the car still on track (or
        held) is DeepRacer's "time up"."""
        trace = self.finish()
        if len(trace) > 1 and int(trace.status[-1]) in (IN_PROGRESS, PAUSE):
            trace.status[-1] = TIME_UP
        return trace

    def finish(self) -> RaceTrace:
        n = self._n
        f32 = self._f32[:n]
        return RaceTrace(
            t=self._t[:n].copy(),
            x=f32[:, 0].copy(),
            y=f32[:, 1].copy(),
            heading=f32[:, 2].copy(),
            speed=f32[:, 3].copy(),
            steering=f32[:, 4].copy(),
            throttle=f32[:, 5].copy(),
            action=self._action[:n].copy(),
            status=self._status[:n].copy(),
            lap=self._lap[:n].copy(),
            offtrack=self._flags[:n, 0].copy(),
            all_wheels_on=self._flags[:n, 1].copy(),
            progress=f32[:, 6].copy(),
            waypoint=self._waypoint[:n].copy(),
            pause=f32[:, 7].copy(),
            track_length=self._track_length,
        )

"""Replaying recorded races: ticks rebuilt from a result's trace, and ghost laps.

A recorded race (a RaceResult with its RaceTrace, from the league or a sim-trace CSV)
plays back through the same RaceTick stream a live race produces, so one view draws both.
A ghost is one lap of a trace, positioned by time since its lap started, drawn beside
the car for comparison.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.race.engine import RaceTick
from sim.race.result import LapRecord, RaceResult

_EPS = 1e-6


@dataclass(frozen=True, eq=False)
class GhostLap:
    """One lap's path by time since the lap started."""

    lap_seconds: float
    times: NDArray[np.float64]  # seconds since the lap started, increasing
    xy: NDArray[np.float64]  # (N, 2) car centre

    def position(self, lap_time: float) -> tuple[float, float]:
        """Where the ghost is `lap_time` seconds into its lap (it waits at the line after)."""
        t = min(max(lap_time, 0.0), float(self.times[-1]))
        return (
            float(np.interp(t, self.times, self.xy[:, 0])),
            float(np.interp(t, self.times, self.xy[:, 1])),
        )


def ghost_lap(result: RaceResult, lap: LapRecord | None = None) -> GhostLap | None:
    """The ghost of `lap` (default: the result's best lap), or None without a trace."""
    lap = lap if lap is not None else result.best_lap
    trace = result.trace
    if lap is None or trace is None:
        return None
    end = lap.started_at + lap.time_seconds
    rows = np.flatnonzero((trace.t >= lap.started_at - _EPS) & (trace.t <= end + _EPS))
    if len(rows) < 2:
        return None
    times = trace.t[rows] - lap.started_at
    xy = np.stack([trace.x[rows], trace.y[rows]], axis=1).astype(np.float64)
    return GhostLap(lap.time_seconds, times, xy)


def replay_ticks(result: RaceResult) -> list[RaceTick]:
    """The race's ticks rebuilt from its trace; empty when the result carries no trace."""
    trace = result.trace
    if trace is None or len(trace) == 0:
        return []
    laps = result.laps
    lap_ends = [lap.started_at + lap.time_seconds for lap in laps]
    statuses = trace.statuses()
    offtrack_starts = np.flatnonzero(
        trace.offtrack & ~np.concatenate([[False], trace.offtrack[:-1]])
    )
    start_times = trace.t[offtrack_starts].tolist()
    window = result.rules.window_seconds
    ticks: list[RaceTick] = []
    last = len(trace) - 1
    for i in range(len(trace)):
        clock = float(trace.t[i])
        done = bisect_right(lap_ends, clock + _EPS)
        lap_start = lap_ends[done - 1] if done else 0.0
        lap_offtracks = bisect_right(start_times, clock + _EPS) - bisect_right(
            start_times, lap_start + _EPS
        )
        ticks.append(
            RaceTick(
                step=i,
                clock=clock,
                window_seconds=window,
                x=float(trace.x[i]),
                y=float(trace.y[i]),
                heading=float(trace.heading[i]),
                speed=float(trace.speed[i]),
                lap=done + 1,
                lap_time=max(clock - lap_start, 0.0),
                progress=float(trace.progress[i]),
                laps=laps[:done],
                lap_offtracks=max(lap_offtracks, 0),
                offtrack=bool(trace.offtrack[i]),
                status=statuses[i],
                penalty_remaining=0.0,
                result=result if i == last else None,
            )
        )
    return ticks

"""Replaying recorded races: ticks rebuilt from a result's trace, and ghost laps.

A recorded race (a RaceResult with its RaceTrace, from the league or a sim-trace CSV)
plays back through the same RaceTick stream a live race produces, so one view draws both.
A ghost is one lap of a trace, positioned by time since its lap started, drawn beside
the car for comparison.
"""

from __future__ import annotations

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
    # Whole columns at once (a 4-minute race is 3,600 rows, rebuilt as its replay opens).
    lap_ends = np.array([lap.started_at + lap.time_seconds for lap in laps], dtype=np.float64)
    clocks = trace.t.astype(np.float64)
    done = np.searchsorted(lap_ends, clocks + _EPS, side="right")
    lap_starts = np.concatenate([[0.0], lap_ends])[done]  # 0 before the first lap ends
    offtrack_starts = np.flatnonzero(
        trace.offtrack & ~np.concatenate([[False], trace.offtrack[:-1]])
    )
    start_times = clocks[offtrack_starts]
    lap_offtracks = np.searchsorted(start_times, clocks + _EPS, side="right") - np.searchsorted(
        start_times, lap_starts + _EPS, side="right"
    )
    laps_done = [laps[:n] for n in range(len(laps) + 1)]
    window = result.rules.window_seconds
    last = len(trace) - 1
    rows = zip(
        clocks.tolist(),
        trace.x.tolist(),
        trace.y.tolist(),
        trace.heading.tolist(),
        trace.speed.tolist(),
        done.tolist(),
        np.maximum(clocks - lap_starts, 0.0).tolist(),
        trace.progress.tolist(),
        np.maximum(lap_offtracks, 0).tolist(),
        trace.offtrack.tolist(),
        trace.statuses(),
        strict=True,
    )
    return [
        RaceTick(
            step=i,
            clock=clock,
            window_seconds=window,
            x=x,
            y=y,
            heading=heading,
            speed=speed,
            lap=n_done + 1,
            lap_time=lap_time,
            progress=progress,
            laps=laps_done[n_done],
            lap_offtracks=offtracks,
            offtrack=offtrack,
            status=status,
            penalty_remaining=0.0,
            result=result if i == last else None,
        )
        for i, (
            clock,
            x,
            y,
            heading,
            speed,
            n_done,
            lap_time,
            progress,
            offtracks,
            offtrack,
            status,
        ) in enumerate(rows)
    ]

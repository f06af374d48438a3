"""Replaying recorded races: ticks rebuilt from a result's trace, and ghost laps.

A recorded race (a RaceResult with its RaceTrace, from the league or a sim-trace CSV)
plays back through the same RaceTick stream a live race produces, so one view draws both.
A race among boxes or bot cars replays them too: they are placed again from the rules and
the race's seed, and the bots driven again along the trace's clock, as the race drove them
(on while the car drove or was held, stopped when one ran into the car from behind).
A ghost is one lap of a trace, positioned by time since its lap started, drawn beside
the car for comparison.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from sim.physics.car import DEEPRACER_CAR, STEP_SECONDS
from sim.physics.objects.settings import RaceType
from sim.physics.objects.world import object_field
from sim.physics.simulation import LOOK_AHEAD
from sim.race.engine import RaceTick
from sim.race.result import LapRecord, RaceResult
from sim.race.trace import PAUSE_STATUS, STATUS_CODE
from sim.tracks.track import Track

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


def replay_ticks(result: RaceResult, track: Track | None = None) -> list[RaceTick]:
    """The race's ticks rebuilt from its trace; empty when the result carries no trace.
    With the race's `track`, a race among boxes or bots shows them too."""
    ticks = _car_ticks(result)
    if track is None or result.rules.race_type is RaceType.TIME_TRIAL or not ticks:
        return ticks
    return [
        replace(tick, objects=objects)
        for tick, objects in zip(ticks, _replayed_objects(result, track, ticks), strict=True)
    ]


def _replayed_objects(
    result: RaceResult, track: Track, ticks: list[RaceTick]
) -> list[tuple[tuple[float, float, float], ...]]:
    """Where the race's objects were on each tick (see the module docstring)."""
    field = object_field(track, result.rules.race_settings, 1, seed=result.seed)
    if field is None:
        return [()] * len(ticks)
    centre = track.centerline
    shown = []
    previous = 0.0
    for tick in ticks:
        if tick.step > 0:
            if tick.status == PAUSE_STATUS:
                field.pass_time(0, tick.clock - previous)
            else:
                field.advance(STEP_SECONDS)
                yaw = math.radians(tick.heading)
                ahead = np.array(
                    [[tick.x + LOOK_AHEAD * math.cos(yaw), tick.y + LOOK_AHEAD * math.sin(yaw)]]
                )
                seg, t, _ = centre.project(ahead)
                field.crashed(
                    np.array([tick.x]),
                    np.array([tick.y]),
                    np.array([yaw]),
                    centre.arc_length(seg, t),
                    DEEPRACER_CAR,
                )
        previous = tick.clock
        shown.append(
            tuple(
                (x, y, math.degrees(h))
                for x, y, h in zip(
                    field.x[0].tolist(), field.y[0].tolist(), field.heading[0].tolist(), strict=True
                )
            )
        )
    return shown


def _car_ticks(result: RaceResult) -> list[RaceTick]:
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
    lap_offtracks = _in_lap(clocks[offtrack_starts], clocks, lap_starts)
    crash_times = clocks[trace.status == STATUS_CODE["crashed"]]
    lap_crashes = _in_lap(crash_times, clocks, lap_starts)
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
        np.maximum(lap_crashes, 0).tolist(),
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
            lap_crashes=crashes,
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
            crashes,
            offtrack,
            status,
        ) in enumerate(rows)
    ]


def _in_lap(
    times: NDArray[np.float64], clocks: NDArray[np.float64], lap_starts: NDArray[np.float64]
) -> NDArray[np.int64]:
    """For each row, how many of `times` fall in its lap so far."""
    return np.asarray(
        np.searchsorted(times, clocks + _EPS, side="right")
        - np.searchsorted(times, lap_starts + _EPS, side="right")
    )

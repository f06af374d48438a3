"""Where a lap loses time against the limit lap, sector by sector.

A lap is its car's path: times, centre positions and speeds from crossing the start line
to crossing it again (`DrivenPath`), read from a race's trace (`path_of_race_lap`) or a
DeepRacer sim-trace's trial (`path_of_trial`). Each sector (`sim.coach.sectors`) gets:
- its time and the limit lap's (the standing limit for a lap from rest, the flying one
  for a lap begun at speed), and the time lost;
- how far, on average, the car was from the limit lap's line;
- its speed against the limit lap's speed where it was (the mean gap, and at the slowest
  point of a corner);
- in a corner, where the car began to slow against where the limit lap does (metres
  along the centre line, "brakes 0.6 m early").
`coach_sentence` says the largest of these in plain words.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.coach.limit_lap import LimitLap
from sim.coach.sectors import Sector, centre_positions, unwrapped
from sim.deepracer.files import SimTraceRow
from sim.foundation.arrays import FloatArray
from sim.foundation.remedies import RemedyError
from sim.physics.simulation import LOOK_AHEAD
from sim.race.trace import RaceTrace
from sim.tracks.geometry import PolylineProjector
from sim.tracks.track import Track

_OFF_LINE = 0.10  # metres from the line worth a word
_SLOWER = 0.15  # m/s under the limit's speed worth a word
_BRAKING = 0.3  # metres of braking point worth a word


class LapAnalysisError(RemedyError):
    """A lap that cannot be analysed; the message says why and what to do."""


@dataclass(frozen=True)
class DrivenPath:
    """One lap of a car: times (s, from the line), its centre (x, y) and speed (m/s)."""

    t: FloatArray
    x: FloatArray
    y: FloatArray
    speed: FloatArray
    from_rest: bool  # the lap began standing on the line (a trial, a race's first lap)
    label: str  # "trial 2", "lap 5"
    # The lap's time as it was timed (a race's lap, an evaluation's trial, penalties in),
    # when known; else the crossings of the line by the car's centre.
    official_seconds: float | None = None


@dataclass(frozen=True)
class SectorReport:
    sector: Sector
    seconds: float
    limit_seconds: float
    off_line: float  # mean distance from the limit lap's line, metres
    speed_gap: float  # mean speed minus the limit's where the car was, m/s
    apex_gap: float  # slowest speed minus the limit's slowest, m/s (corners)
    braking_gap: float  # metres: negative = began slowing earlier than the limit lap

    @property
    def lost(self) -> float:
        return self.seconds - self.limit_seconds

    @property
    def lost_text(self) -> str:
        """ "+0.21 s", never "-0.00 s"."""
        shown = round(self.lost, 2) or 0.0  # -0.0 is falsy: a nil loss has no sign to show
        return f"{shown:+.2f} s"


@dataclass(frozen=True, eq=False)
class LapTrace:
    """The lap row by row, for drawing it: where each row is along the track, and the car's
    speed there beside the limit lap's."""

    along: FloatArray  # metres along the centre line from the start line, never decreasing
    speed: FloatArray  # m/s
    target: FloatArray  # m/s, the limit lap's speed at the nearest point of its line

    def sector_index(self, sectors: Sequence[Sector]) -> NDArray[np.intp]:
        """Each row's sector (an index into `sectors`, which run from the start line)."""
        starts = np.array([sector.start for sector in sectors])
        return np.clip(np.searchsorted(starts, self.along, side="right") - 1, 0, len(starts) - 1)

    def resampled(self, count: int) -> tuple[FloatArray, FloatArray]:
        """(speed, target) at `count` evenly spaced points from the start line to the end."""
        at = np.linspace(float(self.along[0]), float(self.along[-1]), count)
        return np.interp(at, self.along, self.speed), np.interp(at, self.along, self.target)


@dataclass(frozen=True)
class LapReport:
    label: str
    seconds: float
    limit_seconds: float  # the limit lap of the same kind (standing or flying)
    flying_limit: float
    sectors: tuple[SectorReport, ...]
    trace: LapTrace
    from_rest: bool = False  # a standing lap: its sectors are timed against the standing limit

    @property
    def gap_percent(self) -> float:
        """The lap over the flying limit lap, percent."""
        return (self.seconds / self.flying_limit - 1.0) * 100.0

    @property
    def gap_words(self) -> str:
        """ "2.4 % over the flying limit lap" (a lap can beat it: the limit lap keeps all four
        wheels on the road, the rules only one)."""
        side = "over" if self.gap_percent >= 0.0 else "under"
        return f"{abs(self.gap_percent):.1f} % {side} the flying limit lap"

    def notes(self) -> list[str]:
        """What the headline figure does not say: which limit the sectors are timed against,
        and why a lap may beat a limit lap."""
        notes = []
        if self.from_rest:
            notes.append(
                f"The lap starts from rest, so its sectors are timed against the standing "
                f"limit lap ({self.limit_seconds:.3f} s)."
            )
        if any(report.lost <= -0.005 for report in self.sectors):
            notes.append(
                "The limit lap keeps all four wheels on the road; this lap cuts further in "
                "places (DeepRacer counts a car off only when all four are off)."
            )
        return notes

    def ranked(self) -> list[SectorReport]:
        return sorted(self.sectors, key=lambda report: report.lost, reverse=True)


def path_of_race_lap(trace: RaceTrace, lap: int, official: float | None = None) -> DrivenPath:
    """Lap `lap` (1-based) of a race's trace, from the row that crossed into it to the row
    that crossed out of it; `official` its time as the race timed it."""
    rows = np.flatnonzero(trace.lap == lap)
    if len(rows) < 3 or int(trace.lap.max()) <= lap:
        raise LapAnalysisError(f"the race has no finished lap {lap}.")
    first, last = max(int(rows[0]) - 1, 0), min(int(rows[-1]) + 1, len(trace) - 1)
    pick = slice(first, last + 1)
    return DrivenPath(
        t=trace.t[pick] - trace.t[first],
        x=trace.x[pick].astype(np.float64),
        y=trace.y[pick].astype(np.float64),
        speed=trace.speed[pick].astype(np.float64),
        from_rest=lap == 1,
        label=f"lap {lap}",
        official_seconds=official,
    )


def path_of_trial(
    rows: Sequence[SimTraceRow], trial: int, official: float | None = None
) -> DrivenPath:
    """Trial `trial` (its `episode` number) of a DeepRacer sim-trace, if it completed its
    lap. A row's pose is the car's at the row before's `tstamp`, the lap's last row's at its
    own (DeepRacer's row timing); X, Y are the point 0.14 m ahead of the car's centre."""
    mine = [row for row in rows if row.episode == trial]
    if len(mine) < 3 or mine[-1].episode_status != "lap_complete":
        raise LapAnalysisError(f"trial {trial} of the trace did not complete its lap.")
    # The last row shows the line crossed, at its own time (`sim.training.trace_pose`).
    times = [mine[0].tstamp] + [row.tstamp for row in mine[:-2]] + [mine[-1].tstamp]
    yaw = np.radians([row.yaw for row in mine])
    x = np.array([row.x for row in mine]) - LOOK_AHEAD * np.cos(yaw)
    y = np.array([row.y for row in mine]) - LOOK_AHEAD * np.sin(yaw)
    t = np.array(times) - times[0]
    moved, dt = np.hypot(np.diff(x), np.diff(y)), np.diff(t)
    # The first two rows share a time stamp (each row's pose is at the row before's): a
    # step without time takes the speed of the step after it.
    timed = np.flatnonzero(dt > 1e-6)
    if len(timed) == 0:
        raise LapAnalysisError(f"trial {trial} of the trace has no time between its rows.")
    after = timed[np.minimum(np.searchsorted(timed, np.arange(len(dt))), len(timed) - 1)]
    speed = np.concatenate([[0.0], moved[after] / dt[after]])
    return DrivenPath(
        t, x, y, speed, from_rest=True, label=f"trial {trial}", official_seconds=official
    )


def analyse_lap(
    track: Track, limit: LimitLap, sectors: Sequence[Sector], path: DrivenPath
) -> LapReport:
    length = track.length
    along = unwrapped(centre_positions(track, np.stack([path.x, path.y], axis=1)), length)
    along -= length * math.floor((along[0] + length / 2.0) / length)  # starts near 0
    reach = np.maximum.accumulate(along)
    if reach[-1] < length * 0.98:
        raise LapAnalysisError(f"{path.label} does not go round the whole track.")
    limit_speeds = limit.standing_speeds if path.from_rest else limit.speeds
    limit_along = unwrapped(centre_positions(track, limit.points), length)
    limit_along -= limit_along[0]
    limit_times = _times(limit.distances, limit_speeds)
    line = PolylineProjector(limit.points)
    segment, t, foot = line.project(np.stack([path.x, path.y], axis=1))
    off = np.hypot(path.x - foot[:, 0], path.y - foot[:, 1])
    target = np.interp(line.arc_length(segment, t), line.cumulative, limit_speeds)
    reports = []
    for sector in sectors:
        inside = (reach >= sector.start) & (reach <= sector.end)
        if not inside.any():  # a sector shorter than one step: the row nearest its middle
            inside[int(np.argmin(np.abs(reach - 0.5 * (sector.start + sector.end))))] = True
        seconds = float(
            np.interp(sector.end, reach, path.t) - np.interp(sector.start, reach, path.t)
        )
        limit_seconds = float(
            np.interp(sector.end, limit_along, limit_times)
            - np.interp(sector.start, limit_along, limit_times)
        )
        apex_gap = braking_gap = 0.0
        if sector.corner:
            apex_gap = float(np.min(path.speed[inside]) - np.min(target[inside]))
            braking_gap = _braking_gap(reach[inside], path.speed[inside], target[inside])
        reports.append(
            SectorReport(
                sector,
                seconds,
                limit_seconds,
                off_line=float(np.mean(off[inside])),
                speed_gap=float(np.mean(path.speed[inside] - target[inside])),
                apex_gap=apex_gap,
                braking_gap=braking_gap,
            )
        )
    limit_lap_seconds = limit.standing_seconds if path.from_rest else limit.flying_seconds
    crossing = float(np.interp(length, reach, path.t) - np.interp(0.0, reach, path.t))
    seconds = path.official_seconds if path.official_seconds is not None else crossing
    return LapReport(
        path.label,
        seconds,
        limit_lap_seconds,
        limit.flying_seconds,
        tuple(reports),
        LapTrace(reach, path.speed, target),
        from_rest=path.from_rest,
    )


def _times(distances: FloatArray, speeds: FloatArray) -> FloatArray:
    steps = np.diff(distances)
    return np.concatenate(
        [[0.0], np.cumsum(2.0 * steps / np.maximum(speeds[:-1] + speeds[1:], 1e-9))]
    )


def _braking_gap(along: FloatArray, speed: FloatArray, target: FloatArray) -> float:
    """Metres between where the car's speed peaks before the corner's slowest point and
    where the limit lap's does (negative: the car began slowing earlier)."""
    if len(along) < 3:
        return 0.0
    car_slowest, limit_slowest = int(np.argmin(speed)), int(np.argmin(target))
    car_peak = int(np.argmax(speed[: car_slowest + 1]))
    limit_peak = int(np.argmax(target[: limit_slowest + 1]))
    return float(along[car_peak] - along[limit_peak])


def coach_sentence(report: SectorReport) -> str:
    """One plain sentence: the time lost, and the largest of what explains it."""
    name = report.sector.name
    if report.lost <= -0.005:
        gained = f"{name}: {-report.lost:.2f} s faster than the limit lap"
        if report.off_line >= _OFF_LINE:
            gained += f", {report.off_line:.2f} m off its line"
        return f"{gained} (which keeps all four wheels on the road)."
    if report.lost <= 0.005:
        return f"{name}: no time lost against the limit lap."
    causes: list[tuple[float, str]] = []
    if report.sector.corner and report.braking_gap <= -_BRAKING:
        causes.append((-report.braking_gap, f"brakes {-report.braking_gap:.1f} m early"))
    if report.sector.corner and report.braking_gap >= _BRAKING:
        causes.append((report.braking_gap, f"brakes {report.braking_gap:.1f} m late"))
    if report.sector.corner and report.apex_gap <= -_SLOWER:
        causes.append(
            (-report.apex_gap * 3.0, f"{-report.apex_gap:.1f} m/s slower at the slowest point")
        )
    if report.speed_gap <= -_SLOWER:
        causes.append(
            (-report.speed_gap * 3.0, f"{-report.speed_gap:.1f} m/s under the target speed")
        )
    if report.off_line >= _OFF_LINE:
        causes.append((report.off_line * 5.0, f"{report.off_line:.2f} m off the line"))
    said = ", ".join(text for _, text in sorted(causes, reverse=True)[:2])
    lost = f"{report.lost:.2f} s lost"
    return f"{name}: {said}, {lost}." if said else f"{name}: {lost}."

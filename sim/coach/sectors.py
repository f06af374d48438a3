"""A track split into sectors by the limit lap's curvature: each corner ("T1", "T2", ...)
and each straight between them ("S1", ...), numbered from the start line.

Sectors are stretches of the centre line (arc lengths from its first waypoint), so any
car's lap maps onto them by projecting its positions onto the centre line, whatever line
it drove. A point of the limit lap's line is in a corner where the line bends more than
`CORNER_CURVATURE` (a radius under 2.5 m: the car is held back there), measured over half
a metre; a corner or straight shorter than `SHORTEST` metres joins its neighbours.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from sim.coach.limit_lap import LimitLap
from sim.foundation.arrays import FloatArray
from sim.tracks.track import Track

CORNER_CURVATURE = 0.4  # 1/m
SHORTEST = 0.75  # metres
_SMOOTHING = 0.5  # metres


@dataclass(frozen=True)
class Sector:
    name: str  # "T1", "S2"
    corner: bool
    start: float  # metres along the centre line
    end: float

    @property
    def length(self) -> float:
        return self.end - self.start


def centre_positions(track: Track, points: FloatArray) -> FloatArray:
    """Each point's arc length along the centre line (its nearest point there)."""
    centre = track.centerline
    segment, t, _ = centre.project(np.asarray(points, dtype=np.float64))
    return np.asarray(centre.arc_length(segment, t))


def unwrapped(along: FloatArray, length: float) -> FloatArray:
    """Arc lengths of a drive round a loop made continuous across the start line (a lap
    starts near 0 and ends near `length`)."""
    steps = np.diff(along)
    steps = (steps + length / 2.0) % length - length / 2.0
    return np.concatenate([[along[0]], along[0] + np.cumsum(steps)])


def track_sectors(track: Track, lap: LimitLap) -> list[Sector]:
    """The corners and straights of `track`, by `lap`'s line (module docstring)."""
    length = track.length
    distances = lap.distances
    spacing = float(distances[-1] / max(len(distances) - 1, 1))
    window = max(1, round(_SMOOTHING / spacing / 2))
    bend = np.abs(lap.curvature[:-1])
    padded = np.concatenate([bend[-window:], bend, bend[:window]])
    smoothed = np.convolve(padded, np.ones(2 * window + 1) / (2 * window + 1), "same")
    cornering = smoothed[window:-window] > CORNER_CURVATURE
    along = centre_positions(track, lap.points[:-1])
    # Runs of corner and straight along the line, as stretches of the centre line.
    firsts = [0, *(np.flatnonzero(np.diff(cornering.astype(np.int8))) + 1).tolist()]
    stretches = [_Stretch(bool(cornering[i]), float(along[i]), 0.0) for i in firsts]
    stretches[0].start = 0.0
    for this, following in itertools.pairwise(stretches):
        this.end = following.start
    stretches[-1].end = length
    merged = _merge_short([stretch for stretch in stretches if stretch.end > stretch.start])
    counts = {True: 0, False: 0}
    sectors = []
    for stretch in merged:
        counts[stretch.corner] += 1
        name = f"{'T' if stretch.corner else 'S'}{counts[stretch.corner]}"
        sectors.append(Sector(name, stretch.corner, stretch.start, stretch.end))
    return sectors


@dataclass
class _Stretch:
    corner: bool
    start: float
    end: float


def _merge_short(stretches: list[_Stretch]) -> list[_Stretch]:
    """Join stretches shorter than SHORTEST to their neighbours (a short straight between
    two corners makes one corner of them; a short bend on a straight is straight)."""
    merged: list[_Stretch] = []
    for stretch in stretches:
        short = stretch.end - stretch.start < SHORTEST
        if merged and (short or merged[-1].corner == stretch.corner):
            merged[-1].end = stretch.end
        else:
            merged.append(stretch)
    if len(merged) > 1 and merged[0].end - merged[0].start < SHORTEST:
        merged[1].start = merged[0].start  # a short first stretch: its follower's kind
        merged.pop(0)
    return merged

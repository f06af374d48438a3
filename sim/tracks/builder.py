"""Build validated tracks from a closed centre line description.

Two descriptions are supported: a chain of straights and circular arcs (exact radii, for
designed circuits) and a ring of control points joined by a periodic cubic spline (smooth
shapes, for the generator). Both become a centre line resampled at DeepRacer's spacing
with exact unit normals; the borders are the centre line offset by half the width along
the left normal, so inner (columns 2-3) is the inside of a counter-clockwise loop.

Every design is checked before it becomes a track: no turn may be so tight that the inner
border folds over itself, and separate parts of the road must keep a strip of grass
between them. `Track.from_array` then runs the same validation as for imported files.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from sim.foundation.arrays import FloatArray
from sim.tracks.geometry import signed_area
from sim.tracks.track import MIN_WIDTH, Track, TrackError

# DeepRacer's own track files space their waypoints about 0.15 m apart.
WAYPOINT_SPACING = 0.15
# A turn must be at least this much wider than half the road, or the inner border shrinks
# to a point and the car has no line through the corner.
MIN_RADIUS_MARGIN = 0.05
# Coordinates start this far from the origin, like DeepRacer's own tracks.
ORIGIN_MARGIN = 0.5
# Rounding to a micrometre keeps the written files byte-identical across platforms whose
# sin/cos differ in the last bit.
_DECIMALS = 6
# Fine enough that the spline's arc length is exact to well under a millimetre.
_SPLINE_SAMPLES_PER_METRE = 400


class TrackDesignError(TrackError):
    """A centre line description that cannot make a drivable track."""


@dataclass(frozen=True)
class Straight:
    """A straight piece; `length=None` lets `close_loop` choose the length that closes the loop."""

    length: float | None = None


@dataclass(frozen=True)
class Arc:
    """A circular turn of the centre line; positive degrees turn left (counter-clockwise)."""

    radius: float
    degrees: float

    @property
    def length(self) -> float:
        return self.radius * math.radians(abs(self.degrees))


Segment = Straight | Arc


@dataclass(frozen=True)
class CentreLine:
    """An open ring of centre points (the closing row is added later) with exact left normals."""

    points: FloatArray
    normals: FloatArray
    length: float
    min_radius: float


# --- straights and arcs -------------------------------------------------------------------


def close_loop(segments: Sequence[Segment], *, heading_deg: float = 0.0) -> list[Segment]:
    """Give the two free straights (`length=None`) the lengths that make the chain a loop.

    Headings do not depend on straight lengths, so the end point is linear in the two free
    lengths: one 2x2 solve closes the loop exactly.
    """
    _check_pieces(segments)
    total_turn = sum(seg.degrees for seg in segments if isinstance(seg, Arc))
    if not math.isclose(abs(total_turn), 360.0, abs_tol=1e-9):
        raise TrackDesignError(
            f"the turns add up to {total_turn:g} degrees; a simple loop turns 360 in total."
        )
    free = [i for i, seg in enumerate(segments) if isinstance(seg, Straight) and seg.length is None]
    if len(free) not in (0, 2):
        raise TrackDesignError(
            f"the design has {len(free)} free straights; give exactly two (or none)."
        )
    fixed: list[Segment] = [Straight(0.0) if i in free else seg for i, seg in enumerate(segments)]
    initial = math.radians(heading_deg)
    gap = -_chain_end(fixed, initial)
    if not free:
        if float(np.hypot(*gap)) > 1e-6:
            raise TrackDesignError(f"the design ends {np.hypot(*gap):.3f} m from where it starts.")
        return fixed
    headings = _start_headings(fixed, initial)
    directions = np.array([[math.cos(headings[i]), math.sin(headings[i])] for i in free]).T
    if abs(np.linalg.det(directions)) < 1e-6:
        raise TrackDesignError(
            "the two free straights are parallel, so they cannot close the loop."
        )
    lengths = np.linalg.solve(directions, gap)
    if np.any(lengths <= 0):
        raise TrackDesignError(
            f"closing the loop needs free straights of {lengths[0]:.2f} m and {lengths[1]:.2f} m; "
            "both must be positive, so adjust the other pieces."
        )
    for index, length in zip(free, lengths, strict=True):
        fixed[index] = Straight(float(length))
    return fixed


def _check_pieces(segments: Sequence[Segment]) -> None:
    for seg in segments:
        if isinstance(seg, Arc) and seg.radius <= 0:
            raise TrackDesignError(f"an arc has radius {seg.radius:g} m; radii must be positive.")
        if isinstance(seg, Straight) and seg.length is not None and seg.length < 0:
            raise TrackDesignError(
                f"a straight is {seg.length:g} m long; lengths cannot be negative."
            )


def _start_headings(segments: Sequence[Segment], initial: float = 0.0) -> list[float]:
    headings = [initial]
    for seg in segments[:-1]:
        headings.append(headings[-1] + (math.radians(seg.degrees) if isinstance(seg, Arc) else 0.0))
    return headings


def _chain_end(segments: Sequence[Segment], initial: float) -> FloatArray:
    position = np.zeros(2)
    for seg, heading in zip(segments, _start_headings(segments, initial), strict=True):
        position = _piece_end(seg, position, heading)
    return position


def _piece_end(seg: Segment, start: FloatArray, heading: float) -> FloatArray:
    points, _ = _along(seg, start, heading, np.array([_seg_length(seg)]))
    return np.asarray(points[0], dtype=np.float64)


def _seg_length(seg: Segment) -> float:
    return float(seg.length or 0.0)


def _along(
    seg: Segment, start: FloatArray, heading: float, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Points and headings at distances `s` along one piece starting at `start`, `heading`."""
    if isinstance(seg, Straight):
        unit = np.array([math.cos(heading), math.sin(heading)])
        return start + s[:, None] * unit, np.full(len(s), heading)
    turn = math.copysign(1.0, seg.degrees)
    # The turn centre sits on the left normal for a left turn, on the right for a right one.
    centre = start + turn * seg.radius * np.array([-math.sin(heading), math.cos(heading)])
    angles = heading + turn * s / seg.radius
    offsets = turn * seg.radius * np.stack([np.sin(angles), -np.cos(angles)], axis=1)
    return centre + offsets, angles


def centre_line_from_segments(
    segments: Sequence[Segment],
    *,
    heading_deg: float = 0.0,
    spacing: float = WAYPOINT_SPACING,
    start_fraction: float = 0.5,
) -> CentreLine:
    """Sample a closed chain of pieces evenly; the first row lies `start_fraction` into piece 0.

    Piece 0 starts at the origin heading `heading_deg` (0 = +x, counter-clockwise positive).
    """
    pieces = close_loop(segments, heading_deg=heading_deg)
    lengths = np.array([_seg_length(seg) for seg in pieces])
    total = float(lengths.sum())
    count = max(3, round(total / spacing))
    s = np.mod(start_fraction * lengths[0] + np.arange(count) * (total / count), total)
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    owner = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(pieces) - 1)
    points = np.empty((count, 2))
    headings = np.empty(count)
    position = np.zeros(2)
    initial = math.radians(heading_deg)
    for index, (seg, heading) in enumerate(
        zip(pieces, _start_headings(pieces, initial), strict=True)
    ):
        mine = owner == index
        points[mine], headings[mine] = _along(seg, position, heading, s[mine] - starts[index])
        position = _piece_end(seg, position, heading)
    radii = [seg.radius for seg in pieces if isinstance(seg, Arc)]
    normals = np.stack([-np.sin(headings), np.cos(headings)], axis=1)
    return CentreLine(points=points, normals=normals, length=total, min_radius=min(radii))


# --- control points -----------------------------------------------------------------------


def centre_line_from_control_points(
    control_points: FloatArray, *, spacing: float = WAYPOINT_SPACING
) -> CentreLine:
    """Join a ring of control points (not repeated at the end) with a periodic cubic spline."""
    ring = np.asarray(control_points, dtype=np.float64)
    if ring.ndim != 2 or ring.shape[1] != 2 or len(ring) < 3:
        raise TrackDesignError("a spline centre line needs at least 3 control points (x, y).")
    closed = np.vstack([ring, ring[:1]])
    chords = np.hypot(*np.diff(closed, axis=0).T)
    if np.any(chords <= 1e-9):
        raise TrackDesignError("two consecutive control points coincide.")
    knots = np.concatenate([[0.0], np.cumsum(chords)])
    spline = CubicSpline(knots, closed, bc_type="periodic")
    t_dense, s_dense, radius = _spline_arc_length(spline, float(knots[-1]))
    total = float(s_dense[-1])
    count = max(3, round(total / spacing))
    t = np.interp(np.arange(count) * (total / count), s_dense, t_dense)
    velocity = spline(t, 1)
    tangents = velocity / np.hypot(*velocity.T)[:, None]
    normals = np.stack([-tangents[:, 1], tangents[:, 0]], axis=1)
    return CentreLine(
        points=np.asarray(spline(t)), normals=normals, length=total, min_radius=radius
    )


def _spline_arc_length(spline: CubicSpline, period: float) -> tuple[FloatArray, FloatArray, float]:
    """Dense parameter grid, arc length along it, and the spline's smallest turn radius."""
    samples = max(2000, math.ceil(period * _SPLINE_SAMPLES_PER_METRE))
    t = np.linspace(0.0, period, samples + 1)
    points = spline(t)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
    first, second = spline(t, 1), spline(t, 2)
    speed = np.hypot(*first.T)
    curvature = np.abs(first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]) / speed**3
    min_radius = float(1.0 / curvature.max()) if curvature.max() > 0 else math.inf
    return t, s, min_radius


# --- from centre line to track ------------------------------------------------------------


def check_turn_radius(line: CentreLine, width: float) -> None:
    """Refuse a turn so tight that the inner border of the road would fold over itself."""
    needed = width / 2 + MIN_RADIUS_MARGIN
    if line.min_radius < needed:
        raise TrackDesignError(
            f"the tightest turn has a {line.min_radius:.3f} m radius; a {width:g} m wide road "
            f"needs at least {needed:.3f} m, so widen that turn or narrow the road."
        )


def track_from_centre_line(
    line: CentreLine,
    name: str,
    *,
    width: float,
    description: str = "",
) -> Track:
    """Offset the borders, place the track near the origin, and validate it as a DeepRacer array."""
    if width < MIN_WIDTH:
        raise TrackDesignError(f"a {width:g} m road is too narrow; make it at least {MIN_WIDTH} m.")
    if signed_area(line.points) <= 0:
        raise TrackDesignError(
            f"track {name!r} runs clockwise; built tracks run counter-clockwise."
        )
    check_turn_radius(line, width)
    half = width / 2
    inner = line.points + half * line.normals
    outer = line.points - half * line.normals
    rows = np.hstack([line.points, inner, outer])
    rows = np.vstack([rows, rows[:1]])
    low = np.minimum(inner.min(axis=0), outer.min(axis=0))
    shift = np.tile(ORIGIN_MARGIN - low, 3)
    array = np.round(rows + shift, _DECIMALS) + 0.0  # + 0.0 turns any -0.0 into 0.0
    return Track.from_array(array, name, description=description)


def build_from_segments(
    name: str,
    segments: Sequence[Segment],
    *,
    width: float,
    description: str = "",
    heading_deg: float = 0.0,
    start_fraction: float = 0.5,
) -> Track:
    """A track from straights and arcs (two free straights close the loop)."""
    line = centre_line_from_segments(
        segments, heading_deg=heading_deg, start_fraction=start_fraction
    )
    return track_from_centre_line(line, name, width=width, description=description)


def build_from_control_points(
    name: str,
    control_points: FloatArray,
    *,
    width: float,
    description: str = "",
) -> Track:
    """A track whose centre line is the periodic spline through `control_points`."""
    line = centre_line_from_control_points(control_points)
    return track_from_centre_line(line, name, width=width, description=description)

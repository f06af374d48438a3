"""Tracks in AWS DeepRacer's own layout, validated.

A track file is a float64 NumPy array of shape (N, 6): centre x,y / inner border x,y /
outer border x,y in metres. It is a loop when the first row equals the last, and the
driving direction is the row order. The road is the outer polygon minus the inner one.

This is the one place that reads and checks track arrays: every error is a `TrackError`
whose message names the file and the problem in one sentence.
"""

from __future__ import annotations

import hashlib
import io
import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

import numpy as np
import shapely
from numpy.lib import format as npy_format
from shapely.geometry import LinearRing, Polygon

from sim.foundation.arrays import FloatArray
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.remedies import echoed, echoed_path
from sim.tracks.errors import TrackError as TrackError  # noqa: PLC0414 (re-exported for callers)
from sim.tracks.geometry import PolylineProjector, segment_lengths, signed_area

Direction = Literal["counter-clockwise", "clockwise"]

# Thinner than this anywhere and the road is not drivable (the car is 0.196 m wide).
MIN_WIDTH = 0.2
# DeepRacer's own tracks are 0.6-1.5 m wide and fit in 30 m; beyond these bounds a file
# is not a track for a 1/18th-scale car (a file in millimetres or kilometres, say), and
# its races would never finish a lap.
MAX_WIDTH = 5.0
MAX_EXTENT_M = 500.0
# Two separate parts of the road (a hairpin's legs, neighbouring straights) must be further
# apart than the car's wheels span diagonally (0.23 m), or a car can sit astride the gap with
# wheels on both parts, never count as off track, and skip the road between them. 0.25 m
# keeps that margin and admits every official DeepRacer loop (Expedition Loop's closest
# approach is 0.28 m).
MIN_ROAD_GAP = 0.25
# An open file whose ends are this close (in median segment lengths) is a loop missing its
# closing row; DeepRacer exports sometimes drop it.
_CLOSE_GAP_SEGMENTS = 3.0
# DeepRacer's own tracks have 22 to 401 waypoints; a dozen times that is plenty for any
# drawn or resampled track, and keeps loading one a matter of milliseconds.
MAX_WAYPOINTS = 5_000
MAX_TRACK_FILE_BYTES = 2_000_000  # 5,000 rows of six float64 is 240 kB
# The road-gap check looks at centre points at least this far apart: finer sampling adds
# nothing to a 0.25 m rule, and would make the pairs it compares grow with its square.
_GAP_CHECK_SPACING = 0.02


@dataclass(frozen=True, eq=False)
class Track:
    """A validated closed track. Build one with `Track.from_array` or `load_track`."""

    name: str
    points: FloatArray
    description: str = ""
    source: str = field(default="", compare=False)

    @classmethod
    def from_array(
        cls, array: object, name: str, *, description: str = "", source: str = ""
    ) -> Track:
        """Validate a DeepRacer (N, 6) array and make a track of it.

        `source` names the file in error messages ("<name>" when there is none).
        """
        label = source or f"track {echoed(name)}"
        points = _normalise(array, label)
        _check_borders(points, label)
        _check_road_gaps(points, label)
        return cls(name=name, points=points, description=description, source=source)

    # --- the three lines -------------------------------------------------------------
    @property
    def center(self) -> FloatArray:
        return self.points[:, 0:2]

    @property
    def inner(self) -> FloatArray:
        return self.points[:, 2:4]

    @property
    def outer(self) -> FloatArray:
        return self.points[:, 4:6]

    # --- derived facts ------------------------------------------------------------------
    @cached_property
    def centerline(self) -> PolylineProjector:
        return PolylineProjector(self.center)

    @cached_property
    def inner_border(self) -> PolylineProjector:
        return PolylineProjector(_dedupe_ring(self.inner))

    @cached_property
    def outer_border(self) -> PolylineProjector:
        return PolylineProjector(_dedupe_ring(self.outer))

    # DeepRacer's two lanes (simapp `track_data.py`): the lines midway between the centre line
    # and each border, where cars are put back and objects stand.
    @cached_property
    def inner_lane(self) -> PolylineProjector:
        return PolylineProjector(_without_repeats((self.inner + self.center) / 2.0))

    @cached_property
    def outer_lane(self) -> PolylineProjector:
        return PolylineProjector(_without_repeats((self.outer + self.center) / 2.0))

    @property
    def length(self) -> float:
        """Centre line length in metres (DeepRacer's `track_length`)."""
        return self.centerline.total_length

    @cached_property
    def widths(self) -> FloatArray:
        """Road width at each waypoint: distance between its inner and outer border points."""
        return np.asarray(np.hypot(*(self.outer - self.inner).T), dtype=np.float64)

    @property
    def width(self) -> float:
        """Typical road width (mean over waypoints, as DeepRacer tools report it), in metres."""
        return float(np.mean(self.widths))

    @property
    def direction(self) -> Direction:
        return "counter-clockwise" if signed_area(self.center[:-1]) > 0 else "clockwise"

    def lateral_extents(self, s: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The road's signed lateral extents (right, left: negative to the right) at
        centre-line arc lengths `s`, measured along each waypoint's normal."""
        centre = self.centerline
        tangents = centre.vectors / centre.lengths[:, None]
        # Tangent at each waypoint: average of the segments meeting there (loop: wraps).
        at_point = tangents + np.roll(tangents, 1, axis=0)
        at_point /= np.maximum(np.hypot(*at_point.T), 1e-12)[:, None]
        at_point = np.vstack([at_point, at_point[:1]])
        normals = np.stack([-at_point[:, 1], at_point[:, 0]], axis=1)
        inner_off = np.einsum("ij,ij->i", self.inner - self.center, normals)
        outer_off = np.einsum("ij,ij->i", self.outer - self.center, normals)
        left = np.maximum(inner_off, outer_off)
        right = np.minimum(inner_off, outer_off)
        return (
            np.interp(s, centre.cumulative, right),
            np.interp(s, centre.cumulative, left),
        )

    def resampled(
        self, spacing: float, least: int = 60
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The centre line every `spacing` metres round the loop (at least `least` points,
        the closing point left out): arc lengths, points, and unit normals (pointing left)
        from tangents smoothed so that they do not jump at the polyline's corners. The
        frame a line across the road is drawn in (`offset * normal` from each point)."""
        centre = self.centerline
        count = max(round(centre.total_length / spacing), least)
        s = np.linspace(0.0, centre.total_length, count, endpoint=False)
        base = centre.point_at(s)
        tangent = centre.direction_at(s)
        for _ in range(3):
            tangent = (np.roll(tangent, 1, axis=0) + tangent + np.roll(tangent, -1, axis=0)) / 3.0
            tangent /= np.hypot(*tangent.T)[:, None]
        normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
        return s, base, normal

    @property
    def waypoints(self) -> list[tuple[float, float]]:
        """Centre points as DeepRacer's `waypoints` param lists them (closing point included)."""
        return [(float(x), float(y)) for x, y in self.center]

    @cached_property
    def road(self) -> Polygon:
        """The drivable surface: outer polygon minus inner polygon (prepared for fast tests)."""
        polygon = Polygon(self.outer, holes=[self.inner])
        shapely.prepare(polygon)
        return polygon

    @cached_property
    def content_hash(self) -> str:
        """SHA-256 of the float64 array: the same track imported twice hashes the same."""
        return hashlib.sha256(np.ascontiguousarray(self.points).tobytes()).hexdigest()

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(min x, min y, max x, max y) over both borders."""
        both = np.vstack([self.inner, self.outer])
        lo, hi = both.min(axis=0), both.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    @cached_property
    def centre_clearance(self) -> FloatArray:
        """Per segment of `centerline`, how far it keeps from the road's edges: its
        distance from the road polygon's rings when the whole segment lies on the road,
        else 0.

        A point nearer than that to a segment is on the road, as `on_road` decides it:
        the line from the point to the segment's nearest point starts on the road and
        crosses no ring, and a point-in-polygon test only changes its answer across a
        ring. A race's car leans on it to skip most of its wheels' polygon tests."""
        centre = self.centerline
        ends = np.stack([centre.starts, centre.starts + centre.vectors], axis=1)
        segments = shapely.linestrings(ends)
        rings = [self.road.exterior, *self.road.interiors]
        edges = []
        for ring in rings:
            points = shapely.get_coordinates(ring)
            edges.append(np.stack([points[:-1], points[1:]], axis=1))
        tree = shapely.STRtree(shapely.linestrings(np.concatenate(edges)))
        _, distance = tree.query_nearest(segments, return_distance=True, all_matches=False)
        middle = centre.starts + centre.vectors / 2.0
        inside = shapely.contains_xy(self.road, middle[:, 0], middle[:, 1])
        return np.where(inside & (distance > 0.0), distance, 0.0)

    def on_road(self, xy: FloatArray) -> np.ndarray:
        """Boolean per point (M, 2): inside the outer border and outside the inner one."""
        pts = np.atleast_2d(xy)
        return np.asarray(shapely.contains_xy(self.road, pts[:, 0], pts[:, 1]))

    def reversed(self) -> Track:
        """The same road driven the other way (row order reversed; inner stays inner)."""
        return Track(
            name=self.name,
            points=np.ascontiguousarray(self.points[::-1]),
            description=self.description,
            source=self.source,
        )

    def renamed(self, name: str, description: str | None = None) -> Track:
        return Track(
            name=name,
            points=self.points,
            description=self.description if description is None else description,
            source=self.source,
        )

    def to_npy_bytes(self) -> bytes:
        buffer = io.BytesIO()
        np.save(buffer, self.points, allow_pickle=False)
        return buffer.getvalue()

    def save(self, path: Path) -> None:
        """Write the DeepRacer .npy file atomically."""
        write_bytes_atomic(path, self.to_npy_bytes())

    def summary(self) -> dict[str, object]:
        return {
            "name": self.name,
            "description": self.description,
            "length_m": round(self.length, 2),
            "width_m": round(self.width, 3),
            "direction": self.direction,
            "waypoints": len(self.points),
        }


def load_track(
    path: Path | str, name: str | None = None, *, description: str = "", reverse: bool = False
) -> Track:
    """Load and validate a DeepRacer .npy track file."""
    file = Path(path)
    label = echoed_path(file)
    try:
        size = file.stat().st_size
    except OSError:  # none there, or a name no file can have (too long, say)
        raise TrackError(
            f"{label}: no such file; give the path of a DeepRacer .npy track file."
        ) from None
    if size > MAX_TRACK_FILE_BYTES:
        raise TrackError(
            f"{label}: is {size:,} bytes; a track file is at most "
            f"{MAX_TRACK_FILE_BYTES:,} (up to {MAX_WAYPOINTS:,} waypoints); resample it."
        )
    try:
        array = _read_npy(file, label, size)
    except OSError as exc:
        raise TrackError(f"{label}: cannot be read ({exc.strerror}).") from None
    track = Track.from_array(array, name or file.stem, description=description, source=label)
    return track.reversed() if reverse else track


def _read_npy(file: Path, label: str, size: int) -> np.ndarray[Any, np.dtype[Any]]:
    """The array in a .npy file, read only after its header has been checked against the
    file: the header says how much to allocate, and a forged one (10^11 rows in a file of
    600 bytes) would otherwise ask for terabytes before any other check could run."""
    with file.open("rb") as handle:
        try:
            version = npy_format.read_magic(handle)
            if version == (1, 0):
                shape, fortran_order, dtype = npy_format.read_array_header_1_0(handle)
            elif version == (2, 0):
                shape, fortran_order, dtype = npy_format.read_array_header_2_0(handle)
            else:
                raise ValueError(f"unsupported .npy version {version}")
            if any(extent < 0 for extent in shape):
                raise ValueError(f"negative extent in shape {shape}")
        except (ValueError, EOFError):
            raise TrackError(
                f"{label}: is not a NumPy .npy file; export the track as a DeepRacer .npy file."
            ) from None
        if dtype.hasobject:
            raise TrackError(
                f"{label}: holds pickled Python objects, which racer-tui never loads; "
                "a track file is a plain float array."
            )
        _check_header(label, tuple(shape), dtype, size - handle.tell())
        count = math.prod(shape)
        data = handle.read(count * dtype.itemsize)
    array = np.frombuffer(data, dtype=dtype, count=count)
    return np.asarray(array.reshape(shape, order="F" if fortran_order else "C"))


def _check_header(label: str, shape: tuple[int, ...], dtype: np.dtype[Any], held: int) -> None:
    """Refuse a header whose array is not a track's, or that claims more data than the file
    holds, before anything is allocated for it."""
    if dtype.kind not in "fiu" or dtype.fields is not None or dtype.subdtype is not None:
        raise TrackError(f"{label}: holds {dtype} values; a track is an array of numbers.")
    claimed = math.prod(shape) * dtype.itemsize
    if claimed > held:
        rows = f"{shape[0]:,} rows" if shape else "a value"
        raise TrackError(
            f"{label}: its header claims {rows} ({claimed:,} bytes) but the file holds only "
            f"{max(held, 0):,} bytes of data, so it is damaged or forged; export the track again."
        )
    if len(shape) != 2 or shape[1] != 6:
        raise TrackError(
            f"{label}: has shape {shape}; a DeepRacer track is (N, 6): "
            "centre x,y, inner border x,y, outer border x,y."
        )


def _normalise(array: object, label: str) -> FloatArray:
    raw = np.asarray(array)
    if raw.dtype.kind not in "fiu":
        raise TrackError(f"{label}: holds {raw.dtype} values; a track is an array of numbers.")
    if raw.ndim != 2 or raw.shape[1] != 6:
        raise TrackError(
            f"{label}: has shape {raw.shape}; a DeepRacer track is (N, 6): "
            "centre x,y, inner border x,y, outer border x,y."
        )
    if len(raw) > MAX_WAYPOINTS + 1:  # the closing row repeats the first
        raise TrackError(
            f"{label}: has {len(raw):,} waypoints; a track may have at most "
            f"{MAX_WAYPOINTS:,} (DeepRacer's have at most 401), so resample it more coarsely."
        )
    points = raw.astype(np.float64)
    bad = ~np.isfinite(points)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise TrackError(
            f"{label}: row {row} holds NaN or infinity; every coordinate must be a number."
        )
    # DeepRacer's own files repeat a centre point now and then; the repeat carries no
    # information and would make a zero-length segment.
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(points[:, 0:2], axis=0)) > 1e-9, axis=1)
    points = points[keep]
    distinct = len(points) - (1 if len(points) > 1 and np.allclose(points[0], points[-1]) else 0)
    if distinct < 3:
        raise TrackError(f"{label}: has {distinct} distinct points; a track needs at least 3.")
    if not np.allclose(points[0, 0:2], points[-1, 0:2]):
        seg = segment_lengths(points[:, 0:2])
        gap = float(np.hypot(*(points[0, 0:2] - points[-1, 0:2])))
        if gap > _CLOSE_GAP_SEGMENTS * float(np.median(seg)):
            raise TrackError(
                f"{label}: is not a closed loop (its ends are {gap:.2f} m apart); "
                "racer-tui races laps, so the last row must repeat the first."
            )
        points = np.vstack([points, points[:1]])
    else:
        points[-1] = points[0]
    return np.ascontiguousarray(points)


def _without_repeats(points: FloatArray) -> FloatArray:
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = np.hypot(*np.diff(points, axis=0).T) > 1e-9
    return np.asarray(points[keep], dtype=np.float64)


def _dedupe_ring(ring: FloatArray) -> FloatArray:
    keep = np.ones(len(ring), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(ring, axis=0)) > 1e-9, axis=1)
    out = ring[keep]
    if not np.allclose(out[0], out[-1]):
        out = np.vstack([out, out[:1]])
    return np.asarray(out, dtype=np.float64)


def _check_borders(points: FloatArray, label: str) -> None:
    widths = np.hypot(*(points[:, 4:6] - points[:, 2:4]).T)
    narrow = np.flatnonzero(widths < MIN_WIDTH)
    if len(narrow):
        row = int(narrow[0])
        raise TrackError(
            f"{label}: the road is {widths[row]:.3f} m wide at waypoint {row}; "
            f"it must be at least {MIN_WIDTH} m wide everywhere."
        )
    if float(widths.max()) > MAX_WIDTH:
        row = int(np.argmax(widths))
        raise TrackError(
            f"{label}: the road is {widths[row]:,.1f} m wide at waypoint {row}; a track for a "
            f"DeepRacer car is at most {MAX_WIDTH:g} m wide (are its units metres?)."
        )
    extent = float(np.ptp(points[:, :6].reshape(-1, 2), axis=0).max())
    if extent > MAX_EXTENT_M:
        raise TrackError(
            f"{label}: the track spans {extent:,.0f} m; a track for a DeepRacer car fits in "
            f"{MAX_EXTENT_M:g} m (are its units metres?)."
        )
    rings = {}
    for name, cols in (
        ("centre line", slice(0, 2)),
        ("inner border", slice(2, 4)),
        ("outer border", slice(4, 6)),
    ):
        ring = _dedupe_ring(points[:, cols])
        if len(ring) < 4:
            raise TrackError(f"{label}: the {name} has fewer than 3 distinct points.")
        linear = LinearRing(ring)
        if not linear.is_simple:
            raise TrackError(
                f"{label}: the {name} crosses itself; a track's lines must not intersect."
            )
        rings[name] = ring
    inner_poly = Polygon(rings["inner border"])
    outer_poly = Polygon(rings["outer border"])
    if LinearRing(rings["inner border"]).intersects(LinearRing(rings["outer border"])):
        raise TrackError(f"{label}: the inner and outer borders cross each other.")
    if inner_poly.area >= outer_poly.area and inner_poly.contains(outer_poly):
        raise TrackError(
            f"{label}: the inner and outer borders are swapped (columns 2-3 must be the "
            "inside of the loop, 4-5 the outside)."
        )
    if not outer_poly.contains(inner_poly):
        raise TrackError(f"{label}: the inner border is not inside the outer border.")
    centre = LinearRing(rings["centre line"])
    road = Polygon(rings["outer border"], holes=[rings["inner border"]])
    if not road.buffer(1e-6).contains(centre):
        raise TrackError(f"{label}: the centre line leaves the road between the borders.")


def _spaced(along: FloatArray, spacing: float) -> np.ndarray:
    """Indices of points at least `spacing` apart along the line (the first always)."""
    buckets = np.floor(along / spacing)
    return np.flatnonzero(np.concatenate([[True], np.diff(buckets) > 0]))


def _check_road_gaps(points: FloatArray, label: str) -> None:
    """Refuse a road that comes back within `MIN_ROAD_GAP` of itself.

    Two waypoints belong to separate parts of the road when the way round between them is
    longer than a half circle whose diameter is their two half-widths plus the gap: any
    bend gentler than that (a hairpin wide enough included) passes, a tighter hairpin or two
    straights laid side by side do not.
    """
    along = np.concatenate([[0.0], np.cumsum(segment_lengths(points[:, 0:2]))])
    kept = _spaced(along[:-1], _GAP_CHECK_SPACING)
    centre = points[:-1, 0:2][kept]
    widths = np.hypot(*(points[:-1, 4:6] - points[:-1, 2:4]).T)[kept]
    along = np.append(along[:-1][kept], along[-1])
    lap = float(along[-1])
    reach = float(widths.max()) + MIN_ROAD_GAP  # no closer pair can be a gap violation
    from scipy.spatial import cKDTree  # noqa: PLC0415 (a slow import, see sim.tracks.geometry)

    pairs = cKDTree(centre).query_pairs(reach, output_type="ndarray")
    if not len(pairs):
        return
    i, j = pairs[:, 0], pairs[:, 1]
    round_trip = np.abs(along[i] - along[j])
    way_round = np.minimum(round_trip, lap - round_trip)
    half_widths = (widths[i] + widths[j]) / 2.0
    separate = way_round > np.pi * (half_widths + MIN_ROAD_GAP) / 2.0
    gaps = np.hypot(*(centre[i] - centre[j]).T) - half_widths
    close = separate & (gaps < MIN_ROAD_GAP)
    if close.any():
        worst = int(np.argmin(np.where(close, gaps, np.inf)))
        # Waypoints as numbered after repeated centre points are dropped.
        a, b = sorted((int(kept[i[worst]]), int(kept[j[worst]])))
        raise TrackError(
            f"{label}: the road passes within {max(gaps[worst], 0.0):.2f} m of itself between "
            f"waypoints {a} and {b}; separate parts of the road must be at least "
            f"{MIN_ROAD_GAP} m apart so a car cannot straddle the gap."
        )

"""Plane geometry on polylines, vectorised over many query points.

Every per-step question the simulator asks of a track ("how far along the centre line is
this car, how far from it, which side") is a projection onto a polyline. Projections are
exact: a KD-tree over densely resampled points finds the right neighbourhood in
O(log n), then the point is projected onto the three segments around it.
"""

from __future__ import annotations

import bisect
import hashlib
import math
import threading
from collections import OrderedDict
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sim.foundation.arrays import FloatArray

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


# Resampling step for the KD-tree. Any step works for exactness as long as segments are
# longer than it; 1 cm keeps the tree small even for a 60 m track.
_SAMPLE_STEP = 0.01
# Lookup grid: each cell remembers the segment nearest its centre, so a per-step query is
# one gather instead of a tree search. A point is at most half a cell diagonal (2.1 cm)
# from its cell centre; checking two segments either side covers that, except near a
# medial axis (inside a hairpin) where far-apart segments are equally close: such cells
# are marked ambiguous and fall back to the exact tree search.
_GRID_CELL = 0.03
_GRID_MARGIN = 1.5
# Only cells this close to the polyline get a precomputed answer: cars never stray further
# from a track's lines than this, and the rest of the bounding box (most of it on a long
# track) falls back to the exact tree search. Building a big track's grid costs a third.
_GRID_BAND = 1.0
# The grid is worth its build (about 0.15 s for a big track's line) only for many
# queries. Until this many points have been asked about in batches (`project`), the exact
# tree search answers: the grid's answers are the same, so this changes no result, and a
# batch amortises the search's overhead. A line only planned against (the reference
# driver's racing line) never builds one. One car's per-step queries (PointProjector)
# build it at once.
_GRID_AFTER = 2000
_NEIGHBOURS = np.arange(-2, 3)
# Built grids, kept for the process by the polyline they were built for: every race, heat
# and replay loads its track afresh (a new Track, new projectors), and building a track's
# three lines' grids again cost 0.1-0.25 s a race. A grid follows from its polyline's
# points alone, so one built for the same points is the same grid. Bounded: a few tracks'
# lines (a big track's grid is about 0.8 MB), the least recently used going first.
_GRIDS_KEPT = 16
_built_grids: OrderedDict[bytes, NDArray[np.intp]] = OrderedDict()
_built_grids_lock = threading.Lock()


def _polyline_key(points: FloatArray) -> bytes:
    """The identity of a polyline's points, for the grid cache."""
    contiguous = np.ascontiguousarray(points, dtype=np.float64)
    digest = hashlib.blake2b(contiguous.tobytes(), digest_size=20)
    digest.update(repr(contiguous.shape).encode())
    return digest.digest()


def segment_lengths(points: FloatArray) -> FloatArray:
    return np.asarray(np.hypot(*np.diff(points, axis=0).T), dtype=np.float64)


class _LookupGrid:
    """The cells around a polyline, each with the segment nearest its centre (or -1 where
    the exact tree search must decide), built on first need: after `_GRID_AFTER` points
    queried in batches, or for one car's per-step queries. Its projector and that
    projector's PointProjector share it, and it refers to neither (a projector keeps its
    PointProjector: a reference back would be a cycle)."""

    def __init__(
        self,
        tree: cKDTree,
        owners: NDArray[np.intp],
        points: FloatArray,
        segments: int,
        closed: bool,
    ) -> None:
        self._tree = tree
        self._owners = owners
        self._key = _polyline_key(points)
        self.segments = segments
        self.closed = closed
        self.origin = points.min(axis=0) - _GRID_MARGIN
        extent = points.max(axis=0) + _GRID_MARGIN - self.origin
        self.shape = (int(np.ceil(extent[0] / _GRID_CELL)), int(np.ceil(extent[1] / _GRID_CELL)))
        self.cells: NDArray[np.intp] | None = None
        self.queries = 0

    def due(self, count: int) -> NDArray[np.intp] | None:
        """The grid once `count` more points make it worth building; None until then."""
        if self.cells is None:
            self.cells = self._kept()  # built already for these points: no reason to wait
        if self.cells is None:
            self.queries += count
            if self.queries >= _GRID_AFTER:
                self.cells = self._kept_or_built()
        return self.cells

    def built(self) -> NDArray[np.intp]:
        """The grid, built now if it has not been."""
        if self.cells is None:
            self.cells = self._kept_or_built()
        return self.cells

    def _kept_or_built(self) -> NDArray[np.intp]:
        """The grid the process built for these points, or a new one (kept, read-only:
        every projector of the same points shares it)."""
        cells = self._kept()
        if cells is not None:
            return cells
        # Built outside the lock: two threads building the same grid build equal ones.
        cells = self._build()
        cells.flags.writeable = False
        with _built_grids_lock:
            _built_grids[self._key] = cells
            _built_grids.move_to_end(self._key)
            while len(_built_grids) > _GRIDS_KEPT:
                _built_grids.popitem(last=False)
        return cells

    def _kept(self) -> NDArray[np.intp] | None:
        with _built_grids_lock:
            cells = _built_grids.get(self._key)
            if cells is not None:
                _built_grids.move_to_end(self._key)
            return cells

    def _build(self) -> NDArray[np.intp]:
        """Nearest segment per cell, or -1 where the exact tree search must decide."""
        nx, ny = self.shape
        band = self._band_cells()
        cells = np.flatnonzero(band.ravel())
        centres = self.origin + (np.stack([cells // ny, cells % ny], axis=1) + 0.5) * _GRID_CELL
        _, nearest = self._tree.query(centres)
        flat = np.full(nx * ny, -1, dtype=np.intp)
        flat[cells] = self._owners[nearest]
        grid = flat.reshape(nx, ny)
        n_seg = self.segments
        padded = np.pad(grid, 1, mode="edge")
        ambiguous = ~band
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                other = padded[1 + dx : 1 + dx + nx, 1 + dy : 1 + dy + ny]
                gap = np.abs(grid - other)
                if self.closed:
                    gap = np.minimum(gap, n_seg - gap)
                # A neighbour outside the band is unknown: decide this cell exactly too.
                ambiguous |= (gap > 1) | (other < 0)
        # The outermost ring also catches every point beyond the grid (indices are clipped).
        ambiguous[[0, -1], :] = True
        ambiguous[:, [0, -1]] = True
        grid[ambiguous] = -1
        return np.asarray(grid.ravel(), dtype=np.intp)

    def _band_cells(self) -> NDArray[np.bool_]:
        """Cells within about `_GRID_BAND` of the polyline (a square dilation of its cells)."""
        nx, ny = self.shape
        samples = self._tree.data
        cell = ((samples - self.origin) / _GRID_CELL).astype(np.intp)
        np.clip(cell, 0, (nx - 1, ny - 1), out=cell)
        mask = np.zeros((nx, ny), dtype=np.int32)
        mask[cell[:, 0], cell[:, 1]] = 1
        reach = int(np.ceil(_GRID_BAND / _GRID_CELL))
        for axis in (0, 1):
            # Sliding-window sum of width 2*reach+1 along one axis, by cumulative sums.
            pad = [(0, 0), (0, 0)]
            pad[axis] = (reach + 1, reach)
            total = np.cumsum(np.pad(mask, pad), axis=axis)
            width = 2 * reach + 1
            upper = [slice(None), slice(None)]
            lower = [slice(None), slice(None)]
            upper[axis] = slice(width, None)
            lower[axis] = slice(None, -width)
            mask = np.minimum(total[tuple(upper)] - total[tuple(lower)], 1)
        return np.asarray(mask > 0)


class PolylineProjector:
    """Projects query points onto a polyline (closed when its first and last points match)."""

    def __init__(self, points: FloatArray) -> None:
        pts = np.asarray(points, dtype=np.float64)
        if len(pts) < 2:
            raise ValueError("a polyline needs at least two points")
        self.points = pts
        self.starts = pts[:-1]
        self.vectors = np.diff(pts, axis=0)
        self.lengths = np.hypot(self.vectors[:, 0], self.vectors[:, 1])
        if np.any(self.lengths <= 0):
            raise ValueError("a polyline must not repeat a point")
        self.cumulative = np.concatenate([[0.0], np.cumsum(self.lengths)])
        self.total_length = float(self.cumulative[-1])
        self.closed = bool(np.allclose(pts[0], pts[-1]))
        self._inv_len_sq = 1.0 / (self.lengths * self.lengths)
        samples, owners = self._resample()
        # Imported here: scipy.spatial takes about 0.1 s to import, which commands that
        # never build a polyline (help, model list, the league's) should not pay.
        from scipy.spatial import cKDTree  # noqa: PLC0415 (start-up: see the comment above)

        self._tree = cKDTree(samples)
        self._owners = owners
        self._lookup = _LookupGrid(self._tree, owners, pts, len(self.lengths), self.closed)
        self._point_projector: PointProjector | None = None  # made by PointProjector.of

    def _resample(self) -> tuple[FloatArray, NDArray[np.intp]]:
        counts = np.maximum(1, np.ceil(self.lengths / _SAMPLE_STEP).astype(np.intp))
        owners = np.repeat(np.arange(len(self.lengths)), counts)
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        t = offsets / counts[owners]
        samples = self.starts[owners] + self.vectors[owners] * t[:, None]
        return samples, owners

    def nearest_segments(self, query: FloatArray) -> NDArray[np.intp]:
        lookup = self._lookup
        cells = lookup.due(len(query))
        if cells is None:
            _, nearest = self._tree.query(query)
            return np.asarray(self._owners[nearest], dtype=np.intp)
        nx, ny = lookup.shape
        cell = ((query - lookup.origin) * (1.0 / _GRID_CELL)).astype(np.intp)
        np.clip(cell, 0, (nx - 1, ny - 1), out=cell)
        seg: NDArray[np.intp] = cells[cell[:, 0] * ny + cell[:, 1]]
        exact = seg < 0
        if exact.any():
            _, nearest = self._tree.query(query[exact])
            seg[exact] = self._owners[nearest]
        return seg

    def project(self, xy: FloatArray) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        """For points (M, 2): nearest segment index, fraction along it, and the nearest point."""
        query = np.atleast_2d(np.asarray(xy, dtype=np.float64))
        seg = self.nearest_segments(query)
        n_seg = len(self.lengths)
        # The closest projection among nearby segments wins.
        candidates = seg[:, None] + _NEIGHBOURS[None, :]
        if self.closed:
            candidates %= n_seg
        else:
            candidates = np.clip(candidates, 0, n_seg - 1)
        rel = query[:, None, :] - self.starts[candidates]
        vec = self.vectors[candidates]
        t = np.einsum("mkd,mkd->mk", rel, vec) * self._inv_len_sq[candidates]
        t = np.minimum(np.maximum(t, 0.0), 1.0)
        foot = self.starts[candidates] + vec * t[..., None]
        dist_sq = np.sum((query[:, None, :] - foot) ** 2, axis=2)
        best = np.argmin(dist_sq, axis=1)
        rows = np.arange(len(query))
        return candidates[rows, best], t[rows, best], foot[rows, best]

    def arc_length(self, seg: NDArray[np.intp], t: FloatArray) -> FloatArray:
        """Distance along the polyline from its first point to (segment, fraction)."""
        return np.asarray(self.cumulative[seg] + t * self.lengths[seg], dtype=np.float64)

    def point_at(self, s: FloatArray) -> FloatArray:
        """Points at arc lengths `s` (wrapped on a closed polyline)."""
        s_arr = np.asarray(s, dtype=np.float64)
        if self.closed:
            s_arr = np.mod(s_arr, self.total_length)
        s_arr = np.clip(s_arr, 0.0, self.total_length)
        seg = np.clip(
            np.searchsorted(self.cumulative, s_arr, side="right") - 1, 0, len(self.lengths) - 1
        )
        t = (s_arr - self.cumulative[seg]) / self.lengths[seg]
        return np.asarray(self.starts[seg] + self.vectors[seg] * t[..., None], dtype=np.float64)

    def direction_at(self, s: FloatArray) -> FloatArray:
        """Unit tangent vectors at arc lengths `s`."""
        s_arr = np.asarray(s, dtype=np.float64)
        if self.closed:
            s_arr = np.mod(s_arr, self.total_length)
        seg = np.clip(
            np.searchsorted(self.cumulative, s_arr, side="right") - 1, 0, len(self.lengths) - 1
        )
        return np.asarray(self.vectors[seg] / self.lengths[seg][..., None], dtype=np.float64)


def signed_area(ring: FloatArray) -> float:
    """Shoelace area: positive for a counter-clockwise ring."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def wrap_degrees(angle: FloatArray | float) -> FloatArray:
    """Wrap to (-180, 180]."""
    wrapped = 180.0 - np.mod(180.0 - np.asarray(angle, dtype=np.float64), 360.0)
    return np.asarray(wrapped, dtype=np.float64)


_NEIGHBOUR_OFFSETS = tuple(int(k) for k in _NEIGHBOURS)


class PointProjector:
    """A `PolylineProjector`'s queries for one point at a time, in plain floats.

    Per-step code for a single car (races) pays more for numpy's per-call overhead than for
    the arithmetic, so these repeat `project`, `point_at` and `direction_at` with Python
    floats: the same method and the same arithmetic, so the same answers (to the last bit
    or so). `project`: the projector's lookup grid names the nearest segment (the exact
    KD-tree decides in ambiguous cells), then the closest projection onto that segment and
    two either side wins, the first on a tie, as `np.argmin` picks.
    """

    @classmethod
    def of(cls, projector: PolylineProjector, *, lazy: bool = False) -> PointProjector:
        """One per projector (tracks cache theirs), so a new race starts without setup.
        The projector keeps it, so it goes when the projector's track goes. (A weak-keyed
        cache kept them all: each value held its key, so no key was ever released, and a
        long session lost about a megabyte of lookup grids per race.) `lazy`: for a few
        hundred queries (one reference lap), the grid is not worth building yet."""
        found = projector._point_projector
        if found is None:
            found = projector._point_projector = cls(projector, lazy=lazy)
        elif not lazy and found._grid is None:
            found._grid = found._lookup.built()
        return found

    def __init__(self, projector: PolylineProjector, *, lazy: bool = False) -> None:
        # What the exact lookup needs, not the projector itself: the projector keeps this
        # object, and a reference back would make a cycle that only a full collection frees.
        self._tree = projector._tree
        self._owners = projector._owners
        self._lookup = projector._lookup
        # One car's per-step queries: a single-point tree search costs about 50 us, far more
        # than the grid's gather, so a race builds the grid at once; a lazy one (a single
        # reference lap) after `_GRID_AFTER` queries, as a batch-queried projector does.
        self._grid = None if lazy else self._lookup.built()
        self._origin_x, self._origin_y = (float(v) for v in self._lookup.origin)
        self._nx, self._ny = self._lookup.shape
        self._inv_cell = 1.0 / _GRID_CELL
        self.starts: list[tuple[float, float]] = [(a, b) for a, b in projector.starts.tolist()]
        self.vectors: list[tuple[float, float]] = [(a, b) for a, b in projector.vectors.tolist()]
        self.lengths: list[float] = projector.lengths.tolist()
        self.cumulative: list[float] = projector.cumulative.tolist()
        self._inv_len_sq: list[float] = projector._inv_len_sq.tolist()
        self._segments = len(self.lengths)
        self._closed = projector.closed
        self.total_length = projector.total_length

    def _segment_at(self, s: float) -> int:
        seg = bisect.bisect_right(self.cumulative, s) - 1
        return 0 if seg < 0 else (self._segments - 1 if seg >= self._segments else seg)

    def point_at(self, s: float) -> tuple[float, float]:
        """The point at arc length `s` (wrapped on a closed polyline)."""
        if self._closed:
            s %= self.total_length
        s = 0.0 if s < 0.0 else (self.total_length if s > self.total_length else s)
        seg = self._segment_at(s)
        t = (s - self.cumulative[seg]) / self.lengths[seg]
        (sx, sy), (vx, vy) = self.starts[seg], self.vectors[seg]
        return sx + vx * t, sy + vy * t

    def direction_at(self, s: float) -> tuple[float, float]:
        """The unit tangent at arc length `s`."""
        if self._closed:
            s %= self.total_length
        seg = self._segment_at(s)
        vx, vy = self.vectors[seg]
        length = self.lengths[seg]
        return vx / length, vy / length

    def arc_length(self, seg: int, t: float) -> float:
        return self.cumulative[seg] + t * self.lengths[seg]

    @property
    def closed(self) -> bool:
        return self._closed

    def distance_sq(self, seg: int, x: float, y: float) -> float:
        """The squared distance from (x, y) to segment `seg`."""
        (sx, sy), (vx, vy) = self.starts[seg], self.vectors[seg]
        t = ((x - sx) * vx + (y - sy) * vy) * self._inv_len_sq[seg]
        t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
        dx, dy = x - sx - vx * t, y - sy - vy * t
        return dx * dx + dy * dy

    def project(self, x: float, y: float) -> tuple[int, float, float, float]:
        """(segment, fraction along it, foot x, foot y) of the nearest point to (x, y)."""
        grid = self._grid
        if grid is None:
            grid = self._grid = self._lookup.due(1)
        seg = -1
        if grid is not None:
            col = int((x - self._origin_x) * self._inv_cell)
            row = int((y - self._origin_y) * self._inv_cell)
            col = 0 if col < 0 else (self._nx - 1 if col >= self._nx else col)
            row = 0 if row < 0 else (self._ny - 1 if row >= self._ny else row)
            seg = int(grid[col * self._ny + row])
        if seg < 0:
            # As the projector's nearest_segments decides without a grid, or in an
            # ambiguous cell: the KD-tree.
            _, nearest = self._tree.query(np.array([[x, y]]))
            seg = int(self._owners[nearest[0]])
        n_seg = self._segments
        starts, vectors, inv_len_sq = self.starts, self.vectors, self._inv_len_sq
        best = (0, 0.0, 0.0, 0.0)
        best_distance = math.inf
        if self._closed:
            candidates = [(seg + k) % n_seg for k in _NEIGHBOUR_OFFSETS]
        else:
            candidates = [min(max(seg + k, 0), n_seg - 1) for k in _NEIGHBOUR_OFFSETS]
        for candidate in candidates:
            sx, sy = starts[candidate]
            vx, vy = vectors[candidate]
            t = ((x - sx) * vx + (y - sy) * vy) * inv_len_sq[candidate]
            if t < 0.0:
                t = 0.0
            elif t > 1.0:
                t = 1.0
            fx, fy = sx + vx * t, sy + vy * t
            distance = (x - fx) ** 2 + (y - fy) ** 2
            if distance < best_distance:
                best_distance = distance
                best = (candidate, t, fx, fy)
        return best

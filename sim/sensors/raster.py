"""A top-down picture of a track, rasterised once and shared by every sensor.

The camera gathers pixels from `texture` (DeepRacer's scene in greyscale, see
`sim.sensors.camera_scene`: a grainy dark road, white bands along its edges, an orange dashed
centre line, a green field and, past the field's edge, the walls). The lidar sphere-traces
through `signed_distance` (the distance to the nearest border line, negative off the
road) and finishes on exact geometry with the border segment `border_segment` names for
each cell. All are plain grids, so a sensor reading for many cars is a few vectorised
gathers instead of geometry.

Grid convention: cell (row j, column i) covers x in [x0 + i*res, x0 + (i+1)*res) and
y in [y0 + j*res, y0 + (j+1)*res); a world point falls in cell floor((p - origin) / res).
"""

from __future__ import annotations

from collections import OrderedDict
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from sim.foundation.arrays import FloatArray
from sim.sensors import camera_scene as scene
from sim.tracks.track import Track

RESOLUTION = 0.01  # metres per cell: the camera's near rows sample the ground at ~2 mm
# Metres around the borders' bounding box: the field up to the walls, and a ring beyond.
MARGIN = 1.0
assert MARGIN > scene.FIELD_MARGIN

# A league night or a training run uses one or two tracks; a handful covers every case
# without keeping stale rasters (tens of MB each for the biggest tracks) alive forever.
_CACHE_SIZE = 4
_cache: OrderedDict[tuple[str, float, float], TrackRaster] = OrderedDict()


class TrackRaster:
    """Grids over the track's bounding box plus a margin; see the module docstring."""

    def __init__(
        self, track: Track, resolution: float = RESOLUTION, margin: float = MARGIN
    ) -> None:
        if resolution <= 0 or margin < 0:
            raise ValueError("resolution must be positive and margin non-negative")
        self.resolution = float(resolution)
        min_x, min_y, max_x, max_y = track.bounds
        self.origin = (min_x - margin, min_y - margin)
        grow = scene.FIELD_MARGIN
        # (min x, min y, max x, max y) of the field: the walls stand on its edge.
        self.field = (min_x - grow, min_y - grow, max_x + grow, max_y + grow)
        self._center = track.center
        self.width = int(np.ceil((max_x - min_x + 2 * margin) / resolution)) + 1
        self.height = int(np.ceil((max_y - min_y + 2 * margin) / resolution)) + 1
        shape = (self.height, self.width)

        self.road: NDArray[np.bool_] = _fill_even_odd([track.outer, track.inner], self, shape)

        # Both borders as one list of segments; `ring_start`/`ring_size` say which ring a
        # segment belongs to, so a sensor can walk to its neighbours around the loop.
        rings = [track.outer_border, track.inner_border]
        self.segment_start: FloatArray = np.vstack([ring.starts for ring in rings])
        self.segment_vector: FloatArray = np.vstack([ring.vectors for ring in rings])
        sizes = [len(ring.starts) for ring in rings]
        self.ring_size: NDArray[np.int32] = np.repeat(sizes, sizes).astype(np.int32)
        self.ring_start: NDArray[np.int32] = np.repeat(np.cumsum([0, *sizes[:-1]]), sizes).astype(
            np.int32
        )
        points, owners = _densify(self.segment_start, self.segment_vector, 0.5 * resolution)
        rows, cols = self._cells(points)
        owner_grid = np.full(shape, -1, dtype=np.int32)
        owner_grid[rows, cols] = owners
        # EDT to the centres of the cells a border passes through: within ~0.7 cell of the
        # true distance to the polyline, which is what sphere tracing needs. The nearest
        # such cell also names a border segment close to every point, so a sensor near a
        # border can finish with exact geometry.
        distance, nearest = distance_transform_edt(
            owner_grid < 0, sampling=resolution, return_indices=True
        )
        self.border_distance: NDArray[np.float32] = np.asarray(distance, dtype=np.float32)
        self.border_segment: NDArray[np.int32] = owner_grid[nearest[0], nearest[1]]

    @classmethod
    def for_track(
        cls, track: Track, resolution: float = RESOLUTION, margin: float = MARGIN
    ) -> TrackRaster:
        """The raster of this track's content, built on first use and then shared."""
        key = (track.content_hash, float(resolution), float(margin))
        raster = _cache.get(key)
        if raster is None:
            raster = cls(track, resolution, margin)
            _cache[key] = raster
            while len(_cache) > _CACHE_SIZE:
                _cache.popitem(last=False)
        else:
            _cache.move_to_end(key)
        return raster

    @property
    def shape(self) -> tuple[int, int]:
        return self.height, self.width

    @cached_property
    def texture(self) -> NDArray[np.uint8]:
        """The ground in DeepRacer's greyscale tones, one per cell (`sim.sensors.camera_scene`);
        cells past the walls, and the outermost ring, hold `BEYOND_WALLS`."""
        shape = self.shape
        texture = _grainy_tiles(scene.GRASS, scene.GRASS_GRAIN, 1, shape)
        road = self.road
        texture[road] = _grainy_tiles(scene.ROAD, scene.ROAD_GRAIN, 2, shape)[road]
        # The bands lie on the road, their outer edge on the border (`border_distance` is
        # good to about 0.7 cell).
        band = road & (self.border_distance <= scene.BORDER_BAND_WIDTH)
        texture[band] = _grainy_tiles(scene.BORDER, scene.BORDER_GRAIN, 3, shape)[band]
        rows, cols = self._dash_cells(self._center)
        texture[rows, cols] = scene.CENTRE
        res = self.resolution
        x0, y0, x1, y1 = self.field
        xs = self.origin[0] + (np.arange(self.width) + 0.5) * res
        ys = self.origin[1] + (np.arange(self.height) + 0.5) * res
        texture[:, (xs < x0) | (xs > x1)] = scene.BEYOND_WALLS
        texture[(ys < y0) | (ys > y1), :] = scene.BEYOND_WALLS
        # Gathers clamp to the outermost cells, so those must read as "past the walls".
        texture[[0, -1], :] = scene.BEYOND_WALLS
        texture[:, [0, -1]] = scene.BEYOND_WALLS
        return texture

    @cached_property
    def signed_distance(self) -> NDArray[np.float32]:
        """Border distance, positive on the road and negative off it (metres).

        A ray crosses a border exactly where this changes sign, so a tracer that overshoots
        the zero-width line still notices, and can interpolate back to the crossing.
        """
        return np.where(self.road, self.border_distance, -self.border_distance).astype(np.float32)

    def cell_of(self, xy: FloatArray) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """(rows, columns) of the cells holding world points (M, 2), clamped to the grid."""
        return self._cells(np.atleast_2d(np.asarray(xy, dtype=np.float64)))

    def _cells(self, xy: FloatArray) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        cols = np.floor((xy[:, 0] - self.origin[0]) / self.resolution).astype(np.intp)
        rows = np.floor((xy[:, 1] - self.origin[1]) / self.resolution).astype(np.intp)
        return np.clip(rows, 0, self.height - 1), np.clip(cols, 0, self.width - 1)

    def _dash_cells(self, center: FloatArray) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        res = self.resolution
        radius = scene.DASH_WIDTH / 2
        points, arc = _densify_with_arc(center, 0.5 * res)
        # Stamp a disc around each sample: the union of discs is a capsule, as long as a
        # dash when the samples stop half a width short of either end.
        phase = np.mod(arc, scene.DASH_LENGTH + scene.DASH_GAP)
        points = points[(phase >= radius) & (phase <= scene.DASH_LENGTH - radius)]
        reach = int(np.ceil(radius / res)) + 1
        offsets = np.arange(-reach, reach + 1)
        local = (points - np.asarray(self.origin)) / res
        base = np.floor(local).astype(np.intp)
        cols = base[:, 0, None, None] + offsets[None, None, :]
        rows = base[:, 1, None, None] + offsets[None, :, None]
        dx = cols + 0.5 - local[:, 0, None, None]
        dy = rows + 0.5 - local[:, 1, None, None]
        inside = dx * dx + dy * dy <= (radius / res) ** 2
        rows, cols = np.broadcast_arrays(rows, cols)
        return (
            np.clip(rows[inside], 0, self.height - 1),
            np.clip(cols[inside], 0, self.width - 1),
        )


def _grainy_tiles(tone: int, spread: float, seed: int, shape: tuple[int, int]) -> NDArray[np.uint8]:
    """A grid of `shape` in `tone` with the scene's fixed grain repeated across it."""
    tile = scene.grainy_tile(tone, spread, seed)
    reps = (-(-shape[0] // tile.shape[0]), -(-shape[1] // tile.shape[1]))
    return np.ascontiguousarray(np.tile(tile, reps)[: shape[0], : shape[1]])


def _densify(
    starts: FloatArray, vectors: FloatArray, step: float
) -> tuple[FloatArray, NDArray[np.int32]]:
    """Points along segments no more than `step` apart, with the segment each lies on."""
    lengths = np.hypot(vectors[:, 0], vectors[:, 1])
    counts = np.ceil(lengths / step).astype(np.intp) + 1
    owners = np.repeat(np.arange(len(lengths), dtype=np.int32), counts)
    offsets = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    t = offsets / (counts[owners] - 1)
    points = starts[owners] + vectors[owners] * t[:, None]
    return np.asarray(points, dtype=np.float64), owners


def _densify_with_arc(polyline: FloatArray, step: float) -> tuple[FloatArray, FloatArray]:
    """Points along a polyline no more than `step` apart, with their arc lengths."""
    starts = polyline[:-1]
    vectors = np.diff(polyline, axis=0)
    lengths = np.hypot(vectors[:, 0], vectors[:, 1])
    counts = np.maximum(1, np.ceil(lengths / step).astype(np.intp))
    owners = np.repeat(np.arange(len(lengths)), counts)
    offsets = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    t = offsets / counts[owners]
    points = starts[owners] + vectors[owners] * t[:, None]
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    arc = cumulative[owners] + t * lengths[owners]
    points = np.vstack([points, polyline[-1:]])
    arc = np.append(arc, cumulative[-1])
    return np.asarray(points, dtype=np.float64), np.asarray(arc, dtype=np.float64)


def _fill_even_odd(
    rings: list[FloatArray], raster: TrackRaster, shape: tuple[int, int]
) -> NDArray[np.bool_]:
    """Cells whose centre lies inside an odd number of rings (outer minus inner = road).

    A scanline fill: every edge toggles the parity of the cells to the right of where it
    crosses each cell-centre row, and a running sum along the row turns toggles into
    insideness. Exact at cell centres and far faster than point-in-polygon tests.
    """
    height, width = shape
    res = raster.resolution
    origin = np.asarray(raster.origin)
    all_rows: list[NDArray[np.intp]] = []
    all_cols: list[NDArray[np.intp]] = []
    for ring in rings:
        # Coordinates in which cell centres sit on integers.
        local = (np.asarray(ring, dtype=np.float64) - origin) / res - 0.5
        a, b = local[:-1], local[1:]
        low = np.minimum(a[:, 1], b[:, 1])
        high = np.maximum(a[:, 1], b[:, 1])
        # Half-open [low, high) so a vertex shared by two edges is counted once.
        first = np.ceil(low).astype(np.intp)
        counts = np.maximum(np.ceil(high).astype(np.intp) - first, 0)
        edges = np.repeat(np.arange(len(a)), counts)
        rows = first[edges] + (
            np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
        )
        ya, yb = a[edges, 1], b[edges, 1]
        xa, xb = a[edges, 0], b[edges, 0]
        x_cross = xa + (rows - ya) * (xb - xa) / (yb - ya)
        cols = np.floor(x_cross).astype(np.intp) + 1
        keep = (rows >= 0) & (rows < height)
        all_rows.append(rows[keep])
        all_cols.append(np.clip(cols[keep], 0, width))
    rows_cat = np.concatenate(all_rows)
    cols_cat = np.concatenate(all_cols)
    toggles = np.bincount(rows_cat * (width + 1) + cols_cat, minlength=height * (width + 1))
    parity = np.cumsum(toggles.reshape(height, width + 1).astype(np.uint8), axis=1, dtype=np.uint8)
    return np.asarray((parity[:, :width] & 1).astype(bool))

"""DeepRacer's sensors for N cars at once: the front camera, the lidar and the sector lidar.

Both sensors read a `TrackRaster` (built once per track) instead of the track geometry,
so one call for a whole batch of cars is a handful of vectorised NumPy passes:

* the camera (`sim.sensors.camera`, re-exported here) is a pinhole looking at a flat ground
  plane, with DeepRacer's walls around the field.
* the lidar sphere-traces the signed border distance: it steps along each ray by the
  distance to the nearest border until it crosses one (the sign changes) or comes close,
  then intersects the ray exactly with the few border segments there, so readings match
  the geometry to a fraction of a millimetre.

Poses are (x, y, yaw): body centre in metres, yaw in radians counter-clockwise from +x.
Sensor objects keep scratch buffers, so use one per thread.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.sensors.camera import (
    DEEPRACER_CAMERA,
    PHYSICAL_CAR_CAMERA,
    Camera,
    CameraSpec,
    camera_space,
    channels_last,
    poses,
)
from sim.sensors.raster import TrackRaster
from sim.tracks.track import Track

__all__ = [
    "DEEPRACER_CAMERA",
    "PHYSICAL_CAR_CAMERA",
    "Camera",
    "CameraSpec",
    "Lidar",
    "LidarSpec",
    "SectorLidar",
    "SectorLidarSpec",
    "camera_space",
    "channels_last",
    "lidar_space",
    "sector_lidar_space",
    "sectors",
]

Float32Array = NDArray[np.float32]

# Lidar marching: over-relaxed steps (checked, see `Lidar._march`) reach grazing hits in
# fewer iterations; the iteration cap bounds the cost of a scan.
_RELAXATION = 1.6
_MAX_ITERATIONS = 12
# A ray this close to a border (cells) is tested exactly against the segments nearby.
_NEAR_CELLS = 4.0
# How far past a near stop (cells) its crossing is looked for: as far as the segments
# around the stop and around the predicted crossing are sure to be the first ones met.
_AHEAD_CELLS = np.float32(16.0)
# Segments on either side of the one nearest a probe point that are tested exactly: a
# probe lies within a cell or so of the crossing, on its segment or the next.
_EXACT_NEIGHBOURS = 1
# Slack (cells) around a marched crossing when accepting an exact one: the field, and so
# the marching, is only good to about a cell.
_WINDOW_CELLS = np.float32(2.0)
# Ray-segment pairs per chunk when testing rays against every segment.
_EXHAUSTIVE_PAIRS = 200_000
# Up to this many cars a scan intersects rays with the segments in range directly.
_FEW_CARS = 2
# Blocks (cells) of the table of segments in range, for those scans.
_NEAR_BLOCK_CELLS = 25.0


# --- lidar --------------------------------------------------------------------------------


@dataclass(frozen=True)
class LidarSpec:
    """A planar scanner at the car centre that sees the track's border lines."""

    rays: int = 64
    fov_deg: float = 360.0
    max_range: float = 2.0
    min_range: float = 0.15

    def __post_init__(self) -> None:
        if self.rays < 1:
            raise ValueError(f"lidar rays {self.rays} must be at least 1")
        if not 0.0 < self.fov_deg <= 360.0:
            raise ValueError(f"lidar field of view {self.fov_deg} must be in (0, 360] degrees")
        if not 0.0 <= self.min_range < self.max_range:
            raise ValueError("lidar ranges must satisfy 0 <= min_range < max_range")

    @property
    def angles_deg(self) -> NDArray[np.float64]:
        """Ray directions relative to the heading, counter-clockwise (0 = straight ahead).

        Ordered counter-clockwise from the rightmost ray, as a ROS laser scan is. A partial
        fan runs from -fov/2 to +fov/2 inclusive; a full circle starts straight behind, so
        ray rays/2 points straight ahead when the count is even.
        """
        if self.fov_deg >= 360.0:
            return np.asarray(-180.0 + np.arange(self.rays) * (360.0 / self.rays))
        if self.rays == 1:
            return np.zeros(1)
        return np.linspace(-self.fov_deg / 2, self.fov_deg / 2, self.rays)


class Lidar:
    """Distances from each car's centre to the first border line along each ray.

    Rays march through the raster's signed border distance (cheap, good to about a cell)
    until they cross a border or come within a few cells of one; there each is intersected
    exactly with the border segments around that spot, so readings are exact. The few rays
    that only graze past a border are intersected with every segment instead. Everything
    inside runs in raster cells and float32.
    """

    def __init__(self, track: Track, spec: LidarSpec | None = None) -> None:
        self.spec = spec or LidarSpec()
        self.track = track
        self.raster = raster = TrackRaster.for_track(track)
        self.angles = np.radians(self.spec.angles_deg)
        res = raster.resolution
        self._field = raster.signed_distance.ravel()  # metres; see `side` in `scan`
        self._nearest_segment = raster.border_segment.ravel()
        self._limit = np.float32(self.spec.max_range / res)
        self._segment_start = ((raster.segment_start - raster.origin) / res).astype(np.float32)
        self._segment_vector = (raster.segment_vector / res).astype(np.float32)
        # float32 in cells leaves a crossing's place along a segment good to ~1e-4 cells
        # (more at grazing angles); 1e-3 cells of slack at each end keeps a ray through a
        # vertex from slipping between the two segments that share it.
        lengths = np.hypot(self._segment_vector[:, 0], self._segment_vector[:, 1])
        self._half_u_range = (0.5 + 1e-3 / np.maximum(lengths, 1e-6)).astype(np.float32)
        window = np.arange(-_EXACT_NEIGHBOURS, _EXACT_NEIGHBOURS + 1)
        within = (np.arange(len(raster.segment_start)) - raster.ring_start)[:, None] + window
        self._candidates = raster.ring_start[:, None] + np.mod(within, raster.ring_size[:, None])
        self._near: _NearSegments | None = None  # built on the first few-car scan

    def scan(self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> Float32Array:
        """(N, rays) float32 distances in metres, clipped to [min_range, max_range]."""
        xs, ys, yaws = poses(x, y, yaw)
        if len(xs) <= _FEW_CARS:
            return self._scan_few(xs, ys, yaws)
        n, count = len(xs), len(self.angles)
        raster = self.raster
        res = raster.resolution
        theta = (yaws[:, None] + self.angles[None, :]).ravel()
        car = np.repeat(np.arange(n), count)
        col0 = ((xs - raster.origin[0]) / res).astype(np.float32)
        row0 = ((ys - raster.origin[1]) / res).astype(np.float32)
        start = self._field[self._cells(col0, row0)]
        # Measure everything as seen from the car's side of the border: a car off the road
        # looks for the crossing onto it, one on the road for the crossing off it.
        on_road = start > 0
        close = np.abs(start) < _NEAR_CELLS * res
        if close.any():
            # Within a cell or so of a border the nearest cell may lie on the other side.
            on_road[close] = self.track.on_road(np.stack([xs[close], ys[close]], axis=1))
        # Folding metres-to-cells into the sign saves a copy of the field in cells.
        side = np.where(on_road, 1.0, -1.0).astype(np.float32) / np.float32(res)
        batch = _Rays(
            ids=np.arange(n * count),
            col=col0[car],
            row=row0[car],
            dx=np.cos(theta).astype(np.float32),
            dy=np.sin(theta).astype(np.float32),
            side=side[car],
            t=np.zeros(n * count, dtype=np.float32),
            g=np.abs(start * side)[car],
            omega=np.full(n * count, _RELAXATION, dtype=np.float32),
        )
        hit = np.full(n * count, self._limit, dtype=np.float32)
        # Marching replaces t, g and omega as it goes; `batch` keeps every ray's origin and
        # direction for the exact tests.
        crossed, near, going = self._march(batch.kept(slice(None)))
        unsettled = [
            self._settle(batch, crossed, hit, around_stop=False).ids,
            self._settle(batch, near, hit, around_stop=True).ids,
            going,
        ]
        self._cast_exhaustively(batch, np.concatenate(unsettled), hit)
        result = hit.reshape(n, count) * np.float32(res)
        np.clip(result, self.spec.min_range, self.spec.max_range, out=result)
        return result

    def _scan_few(
        self, xs: NDArray[np.float64], ys: NDArray[np.float64], yaws: NDArray[np.float64]
    ) -> Float32Array:
        """`scan` for a car or two (a race): every ray against the border segments in range.

        Marching pays a round of numpy calls per iteration whatever the batch size; for one
        car, intersecting all the rays with the few dozen segments that can be within range
        is one round, and exact by construction (the same float32 arithmetic as
        `_crossings`, so readings match the marched ones).
        """
        if self._near is None:
            self._near = _NearSegments(
                self._segment_start, self._segment_vector, self._half_u_range, float(self._limit)
            )
        raster = self.raster
        res = raster.resolution
        result = np.empty((len(xs), len(self.angles)), dtype=np.float32)
        for car in range(len(xs)):
            col = np.float32((xs[car] - raster.origin[0]) / res)
            row = np.float32((ys[car] - raster.origin[1]) / res)
            sx, sy, vx, vy, half_u = self._near.around(float(col), float(row))
            theta = yaws[car] + self.angles
            dx = np.cos(theta).astype(np.float32)[:, None]
            dy = np.sin(theta).astype(np.float32)[:, None]
            wx, wy = sx - col, sy - row
            along = wx * vy - wy * vx  # per segment; the same for every ray
            with np.errstate(divide="ignore", invalid="ignore"):
                denom = dx * vy
                denom -= dy * vx
                t = along / denom
                u = wx * dy
                u -= wy * dx
                u /= denom
            u -= np.float32(0.5)
            np.abs(u, out=u)
            valid = u <= half_u
            valid &= t >= np.float32(-1e-3)
            # Starting the minimum at the range limit also drops crossings beyond it.
            result[car] = np.min(t, axis=1, initial=self._limit, where=valid)
        result *= np.float32(res)
        # np.maximum/np.minimum in place: np.clip's result without its per-call overhead.
        np.maximum(result, np.float32(self.spec.min_range), out=result)
        np.minimum(result, np.float32(self.spec.max_range), out=result)
        return result

    def _march(self, rays: _Rays) -> tuple[_Stops, _Stops, NDArray[np.intp]]:
        """Sphere-trace every ray until it crosses a border, nears one or leaves the range.

        Rays that leave the range drop out (they read max_range); the others come back as
        stops, crossings and near ones, to be settled on exact geometry, or, when out of
        iterations, as the ids of rays still going: those creep up on a border at a
        grazing angle, each step costing a round of numpy calls.
        """
        crossed: list[_Stops] = []
        near: list[_Stops] = []
        for _ in range(_MAX_ITERATIONS):
            if not len(rays.ids):
                break
            step = np.maximum(rays.omega * rays.g, np.float32(1.0))
            t_next = rays.t + step
            g_next = self._field[
                self._cells(rays.col + rays.dx * t_next, rays.row + rays.dy * t_next)
            ]
            g_next *= rays.side
            # An over-relaxed step is safe only while the free discs around both ends cover
            # it; otherwise a thin strip could hide between them. Retry it unrelaxed.
            ok = (rays.omega == 1.0) | (rays.g + np.abs(g_next) >= step)
            over = ok & (g_next <= 0)
            close = ok & ~over & (g_next < _NEAR_CELLS)
            finished = over | close | (ok & (t_next >= self._limit))
            if over.any():
                before, after = rays.g[over], g_next[over]
                # Secant: where the distance, linear across the border, changes sign.
                probe = rays.t[over] + step[over] * before / np.maximum(before - after, 1e-6)
                crossed.append(_Stops(rays.ids[over], rays.t[over], probe, t_next[over]))
            if close.any():
                before, after = rays.g[close], g_next[close]
                # Probe where the distance, falling linearly towards a straight border,
                # would reach zero, if that is not far.
                ahead = after * step[close] / np.maximum(before - after, 1e-6)
                ahead = np.where(before > after, np.minimum(ahead, _AHEAD_CELLS), 0.0)
                reached = t_next[close]
                near.append(_Stops(rays.ids[close], rays.t[close], reached + ahead, reached))
            rays.t = np.where(ok, t_next, rays.t)
            rays.g = np.where(ok, g_next, rays.g)
            rays.omega[~ok] = 1.0
            if finished.any():
                rays = rays.kept(~finished)
        return _Stops.joined(crossed), _Stops.joined(near), rays.ids

    def _settle(
        self, batch: _Rays, stops: _Stops, hit: Float32Array, *, around_stop: bool
    ) -> _Stops:
        """Exact crossings for stopped rays; returns the stops where none was found."""
        if not len(stops.ids):
            return stops
        # A secant probe lies within about a cell of the crossing, on its segment or the
        # next one. A near stop is tested around where the ray stopped and around the
        # predicted crossing, and only that far: a crossing farther on could come after
        # one on another stretch of border that neither probe looks at.
        probes = (stops.reached, stops.probe) if around_stop else (stops.probe,)
        upper = _AHEAD_CELLS + _WINDOW_CELLS if around_stop else _WINDOW_CELLS
        crossing = self._intersect(
            batch,
            stops.ids,
            probes,
            np.maximum(stops.clear - _WINDOW_CELLS, 0),
            stops.reached + upper,
        )
        found = np.isfinite(crossing)
        hit[stops.ids[found]] = crossing[found]
        return stops.kept(~found)

    def _cast_exhaustively(self, batch: _Rays, ids: NDArray[np.intp], hit: Float32Array) -> None:
        """Exact first crossings against every border segment, for the few rays the local
        tests could not settle: they graze past a border, where the raster's cell-sized
        errors blur a near miss and a hit."""
        segments = len(self._segment_start)
        chunk = max(1, _EXHAUSTIVE_PAIRS // segments)
        for first in range(0, len(ids), chunk):
            part = ids[first : first + chunk]
            crossing = self._crossings(
                batch,
                part,
                np.broadcast_to(np.arange(segments), (len(part), segments)),
                np.zeros(len(part), dtype=np.float32),
                np.full(len(part), self._limit, dtype=np.float32),
            )
            hit[part] = np.minimum(crossing, self._limit)

    def _intersect(
        self,
        batch: _Rays,
        ids: NDArray[np.intp],
        probes: tuple[Float32Array, ...],
        lo: Float32Array,
        hi: Float32Array,
    ) -> Float32Array:
        """For rays `ids`: the nearest exact crossing within [lo, hi] cells along each with
        the border segments next to the ones nearest the points `probes` cells along it
        (inf where there is none)."""
        col, row, dx, dy = batch.col[ids], batch.row[ids], batch.dx[ids], batch.dy[ids]
        groups = [
            self._candidates[self._nearest_segment[self._cells(col + dx * p, row + dy * p)]]
            for p in probes
        ]
        segments = groups[0] if len(groups) == 1 else np.concatenate(groups, axis=1)
        return self._crossings(batch, ids, segments, lo, hi)

    def _crossings(
        self,
        batch: _Rays,
        ids: NDArray[np.intp],
        segments: NDArray[np.intp],
        lo: Float32Array,
        hi: Float32Array,
    ) -> Float32Array:
        """Nearest crossing within [lo, hi] cells of each ray `ids` with its row of
        `segments`; inf where there is none."""
        col, row = batch.col[ids][:, None], batch.row[ids][:, None]
        dx, dy = batch.dx[ids][:, None], batch.dy[ids][:, None]
        # Segment starts relative to each ray's origin, and the segments' directions.
        wx = self._segment_start[segments, 0] - col
        wy = self._segment_start[segments, 1] - row
        vx = self._segment_vector[segments, 0]
        vy = self._segment_vector[segments, 1]
        # Solve origin + t * direction = start + u * vector with 2-D cross products; a
        # parallel segment divides by zero and then fails every comparison below.
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = dx * vy - dy * vx
            t = (wx * vy - wy * vx) / denom
            u = (wx * dy - wy * dx) / denom
        valid = np.abs(u - 0.5) <= self._half_u_range[segments]
        valid &= t >= lo[:, None] - 1e-3
        valid &= t <= hi[:, None]
        return np.asarray(np.where(valid, t, np.float32(np.inf)).min(axis=1), dtype=np.float32)

    def _cells(self, col: Float32Array, row: Float32Array) -> NDArray[np.int32]:
        """Flat indices of the raster cells under grid positions, clamped to the grid."""
        raster = self.raster
        cols = np.minimum(np.maximum(col, 0), raster.width - 1).astype(np.int32)
        rows = np.minimum(np.maximum(row, 0), raster.height - 1).astype(np.int32)
        rows *= raster.width
        rows += cols
        return rows


class _NearSegments:
    """For each block of the raster, the border segments within lidar range of any point in
    it, laid out block by block (start x, start y, vector x, vector y, half u range) so a
    scan slices them instead of gathering; points off the grid get every segment."""

    def __init__(
        self, starts: Float32Array, vectors: Float32Array, half_u: Float32Array, limit: float
    ) -> None:
        columns = (starts[:, 0], starts[:, 1], vectors[:, 0], vectors[:, 1], half_u)
        self._all = tuple(np.ascontiguousarray(c) for c in columns)
        lo = starts.min(axis=0) - limit
        hi = (starts + vectors).max(axis=0) + limit
        self._origin = (float(lo[0]), float(lo[1]))
        self._cols = int(np.ceil((hi[0] - lo[0]) / _NEAR_BLOCK_CELLS)) + 1
        self._rows = int(np.ceil((hi[1] - lo[1]) / _NEAR_BLOCK_CELLS)) + 1
        cx = lo[0] + (np.arange(self._cols) + 0.5) * _NEAR_BLOCK_CELLS
        cy = lo[1] + (np.arange(self._rows) + 0.5) * _NEAR_BLOCK_CELLS
        centres = np.stack(np.meshgrid(cx, cy, indexing="ij"), axis=-1).reshape(-1, 2)
        # Any point of a block is within half its diagonal of the centre; a cell of slack
        # covers float32 rounding.
        reach = limit + _NEAR_BLOCK_CELLS * math.sqrt(0.5) + 1.0
        start = starts.astype(np.float64)
        vector = vectors.astype(np.float64)
        length_sq = np.maximum(np.sum(vector * vector, axis=1), 1e-12)
        lists: list[NDArray[np.intp]] = []
        for first in range(0, len(centres), 256):
            part = centres[first : first + 256]
            rel = part[:, None, :] - start[None, :, :]
            along = np.clip(np.einsum("mkd,kd->mk", rel, vector) / length_sq, 0.0, 1.0)
            foot = start[None, :, :] + along[..., None] * vector[None, :, :]
            near = np.hypot(*(part[:, None, :] - foot).transpose(2, 0, 1)) <= reach
            lists.extend(np.flatnonzero(row_mask) for row_mask in near)
        self._offsets: list[int] = np.concatenate(
            [[0], np.cumsum([len(item) for item in lists])]
        ).tolist()
        order = np.concatenate(lists) if lists else np.zeros(0, dtype=np.intp)
        self._blocks = tuple(np.ascontiguousarray(c[order]) for c in columns)

    def around(self, col: float, row: float) -> tuple[Float32Array, ...]:
        """(start x, start y, vector x, vector y, half u range) of the segments near a point."""
        i = math.floor((col - self._origin[0]) / _NEAR_BLOCK_CELLS)
        j = math.floor((row - self._origin[1]) / _NEAR_BLOCK_CELLS)
        if not (0 <= i < self._cols and 0 <= j < self._rows):
            return self._all
        block = i * self._rows + j
        first, last = self._offsets[block], self._offsets[block + 1]
        return tuple(column[first:last] for column in self._blocks)


@dataclass
class _Stops:
    """Where marching stopped rays, in cells along each: the ray is known clear up to
    `clear` and stopped at `reached`; its crossing is looked for around `probe`."""

    ids: NDArray[np.intp]
    clear: Float32Array
    probe: Float32Array
    reached: Float32Array

    @staticmethod
    def joined(parts: list[_Stops]) -> _Stops:
        if not parts:
            nothing = np.zeros(0, dtype=np.float32)
            return _Stops(np.zeros(0, dtype=np.intp), nothing, nothing, nothing)
        return _Stops(
            np.concatenate([p.ids for p in parts]),
            np.concatenate([p.clear for p in parts]),
            np.concatenate([p.probe for p in parts]),
            np.concatenate([p.reached for p in parts]),
        )

    def kept(self, mask: NDArray[np.bool_]) -> _Stops:
        return _Stops(self.ids[mask], self.clear[mask], self.probe[mask], self.reached[mask])


@dataclass
class _Rays:
    """Rays being marched (cells): origin, direction, the side of the border the car is
    on (as +-1/resolution, turning the field's metres into cells), distance along so far,
    the border distance there and the relaxation factor.
    Compacted as rays finish, so later steps only pay for the rays still going."""

    ids: NDArray[np.intp]
    col: Float32Array
    row: Float32Array
    dx: Float32Array
    dy: Float32Array
    side: Float32Array
    t: Float32Array
    g: Float32Array
    omega: Float32Array

    def kept(self, which: NDArray[np.bool_] | NDArray[np.intp] | slice) -> _Rays:
        return _Rays(
            self.ids[which],
            self.col[which],
            self.row[which],
            self.dx[which],
            self.dy[which],
            self.side[which],
            self.t[which],
            self.g[which],
            self.omega[which],
        )


def lidar_space(spec: LidarSpec | None = None) -> gym.spaces.Box:
    spec = spec or LidarSpec()
    return gym.spaces.Box(0.0, spec.max_range, shape=(spec.rays,), dtype=np.float32)


# --- sector lidar -------------------------------------------------------------------------


@dataclass(frozen=True)
class SectorLidarSpec:
    """DeepRacer's SECTOR_LIDAR: the full scan cut into sectors, 1 where a border is close."""

    sectors: int = 8
    threshold: float = 0.5  # metres
    lidar: LidarSpec = field(default_factory=LidarSpec)

    def __post_init__(self) -> None:
        if self.sectors < 1 or self.lidar.rays % self.sectors:
            raise ValueError(
                f"{self.lidar.rays} lidar rays cannot be split into {self.sectors} equal sectors"
            )


def sectors(scan: Float32Array, count: int = 8, threshold: float = 0.5) -> Float32Array:
    """(N, count) float32: 1.0 where a sector's nearest reading is under `threshold` metres.

    Sectors are consecutive blocks of rays, in scan order, as DeepRacer's sector filter
    reshapes the raw scan.
    """
    readings = np.asarray(scan, dtype=np.float32)
    if readings.ndim != 2 or readings.shape[1] % count:
        raise ValueError(f"a scan of shape {readings.shape} cannot be split into {count} sectors")
    nearest = readings.reshape(readings.shape[0], count, -1).min(axis=2)
    return np.asarray(nearest < threshold, dtype=np.float32)


class SectorLidar:
    """A `Lidar` whose scans are reduced to DeepRacer's binary sectors."""

    def __init__(self, track: Track, spec: SectorLidarSpec | None = None) -> None:
        self.spec = spec or SectorLidarSpec()
        self.lidar = Lidar(track, self.spec.lidar)

    def scan(self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> Float32Array:
        return sectors(self.lidar.scan(x, y, yaw), self.spec.sectors, self.spec.threshold)


def sector_lidar_space(spec: SectorLidarSpec | None = None) -> gym.spaces.Box:
    spec = spec or SectorLidarSpec()
    return gym.spaces.Box(0.0, 1.0, shape=(spec.sectors,), dtype=np.float32)

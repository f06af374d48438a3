"""DeepRacer's sensors for N cars at once: the front camera, the lidar and the sector lidar.

Both sensors read a `TrackRaster` (built once per track) instead of the track geometry,
so one call for a whole batch of cars is a handful of vectorised NumPy passes:

* the camera is a pinhole looking at a flat ground plane. For a pitched camera without
  roll every image row sees one line across the ground at a fixed distance ahead, so the
  ground point of pixel (row r, column c) in the car's frame is (forward[r], left[r] *
  u[c]); per call only the car's rotation and translation are applied before gathering
  texture cells.
* the lidar sphere-traces the signed border distance: it steps along each ray by the
  distance to the nearest border, notices the sign change where it crosses one, and
  interpolates back to the crossing.

Poses are (x, y, yaw): body centre in metres, yaw in radians counter-clockwise from +x.
Sensor objects keep scratch buffers, so use one per thread.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.raster import GRASS, SKY, TrackRaster
from sim.track import Track

UInt8Array = NDArray[np.uint8]
Float32Array = NDArray[np.float32]

# Ground farther than this ahead is drawn as plain grass: those rows sit within a pixel of
# the horizon, and capping them keeps every gathered index small enough for int32.
MAX_VIEW_DISTANCE = 30.0
# Pixels gathered per chunk: the working arrays (~16 bytes a pixel) then stay in L2 cache.
_CHUNK_PIXELS = 40_000

# Lidar marching: over-relaxed steps (checked, see `Lidar._march`) reach grazing hits in
# fewer iterations; the iteration caps bound the cost of a scan.
_RELAXATION = 1.6
_MAX_ITERATIONS = 32
# Rounds of marching then exact following; a ray needs a second round only after it
# grazed past a border, a third after grazing past two.
_ROUNDS = 3
# Minimum step in raster cells: the field is only exact to about a cell, so smaller
# steps near a border would stall instead of crossing it.
_MIN_STEP_CELLS = 1.0
# A ray this close to a border (cells) is tested exactly against the segments nearby.
_NEAR_CELLS = 2.0
# Segments on either side of the one nearest the probe point that are tested exactly.
_EXACT_NEIGHBOURS = 3
# Slack (cells) past the marched crossing when accepting an exact one: the field, and so
# the marching, is only good to about a cell.
_WINDOW_CELLS = 2.0
# Cells from the nearest border beyond which an exactly followed ray goes back to marching;
# well past _NEAR_CELLS, so that the field's errors cannot bounce it straight back.
_RESUME_CELLS = 3 * _NEAR_CELLS
# Metres past the exact distance that a step may go when following a grazing ray: every
# probe tests the segments around it for crossings back to the previous probe, and this
# stays well under the length of a track segment (10-30 cm on DeepRacer's tracks), so a
# crossing in the unproven stretch is always among the segments tested.
_EXACT_SLACK = 0.05


# --- camera -------------------------------------------------------------------------------


@dataclass(frozen=True)
class CameraSpec:
    """DeepRacer's front-facing camera: 160x120 greyscale, 120 degrees wide, pitched down."""

    width: int = 160
    height: int = 120
    fov_deg: float = 120.0  # horizontal
    mount_forward: float = 0.12  # metres ahead of the body centre
    mount_height: float = 0.10
    pitch_deg: float = 15.0  # down

    def __post_init__(self) -> None:
        if self.width < 1 or self.height < 1:
            raise ValueError(f"camera size {self.width}x{self.height} must be at least 1x1")
        if not 0.0 < self.fov_deg < 180.0:
            raise ValueError(
                f"camera field of view {self.fov_deg} must be between 0 and 180 degrees"
            )
        if self.mount_height <= 0.0:
            raise ValueError("the camera must be mounted above the ground (mount_height > 0)")


class Camera:
    """Renders what each car's front camera sees, (N, H, W) uint8, from the track raster."""

    def __init__(self, track: Track, spec: CameraSpec | None = None) -> None:
        self.spec = spec or CameraSpec()
        self.raster = TrackRaster.for_track(track)
        width, height = self.spec.width, self.spec.height
        focal = (width / 2) / math.tan(math.radians(self.spec.fov_deg) / 2)
        pitch = math.radians(self.spec.pitch_deg)
        # Pixel centres relative to the principal point, in units of the focal length.
        down = (np.arange(height) + 0.5 - height / 2) / focal
        right = (np.arange(width) + 0.5 - width / 2) / focal
        # A ray through image row `down` descends at this rate per unit along it.
        descent = math.sin(pitch) + down * math.cos(pitch)
        with np.errstate(divide="ignore"):
            scale = np.where(descent > 0, self.spec.mount_height / descent, np.inf)
        forward = scale * (math.cos(pitch) - down * math.sin(pitch))
        ground = (descent > 0) & (forward <= MAX_VIEW_DISTANCE)
        self.horizon_row = int(np.count_nonzero(descent <= 0))  # first row below the horizon
        self.ground_row = height - int(np.count_nonzero(ground))  # first rendered ground row
        rows = slice(self.ground_row, height)
        res = self.raster.resolution
        # Everything pre-divided by the cell size: per call only a rotation remains.
        self._forward_cells = ((forward[rows] + self.spec.mount_forward) / res).astype(np.float32)
        self._lateral_cells = (scale[rows] / res).astype(np.float32)
        self._left_unit = (-right).astype(np.float32)  # left of the car is positive
        self._texture = self.raster.texture.ravel()
        ground_pixels = max(1, (height - self.ground_row) * width)
        self._chunk = max(1, _CHUNK_PIXELS // ground_pixels)
        shape = (self._chunk, height - self.ground_row, width)
        self._gx = np.empty(shape, dtype=np.float32)
        self._gy = np.empty(shape, dtype=np.float32)
        self._ix = np.empty(shape, dtype=np.int32)
        self._iy = np.empty(shape, dtype=np.int32)
        self._pixels = np.empty(shape, dtype=np.uint8)

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of one frame."""
        return self.spec.height, self.spec.width

    def render(
        self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike, out: UInt8Array | None = None
    ) -> UInt8Array:
        """Frames for N poses, (N, H, W) uint8; pass `out` to reuse an output array."""
        xs, ys, yaws = _poses(x, y, yaw)
        n = len(xs)
        height, width = self.shape
        if out is None:
            out = np.empty((n, height, width), dtype=np.uint8)
        elif out.shape != (n, height, width) or out.dtype != np.uint8:
            raise ValueError(f"out must be a uint8 array of shape {(n, height, width)}")
        out[:, : self.horizon_row] = SKY
        out[:, self.horizon_row : self.ground_row] = GRASS
        if self.ground_row == height or n == 0:
            return out

        res = self.raster.resolution
        cos = np.cos(yaws)[:, None]
        sin = np.sin(yaws)[:, None]
        col0 = ((xs - self.raster.origin[0]) / res)[:, None]
        row0 = ((ys - self.raster.origin[1]) / res)[:, None]
        forward, lateral = self._forward_cells[None, :], self._lateral_cells[None, :]
        # Per car and image row, the ground line is (base + slope * left_unit[column]).
        base_x = (col0 + cos * forward).astype(np.float32)[:, :, None]
        slope_x = (-sin * lateral).astype(np.float32)[:, :, None]
        base_y = (row0 + sin * forward).astype(np.float32)[:, :, None]
        slope_y = (cos * lateral).astype(np.float32)[:, :, None]
        grid_w = self.raster.width
        for start in range(0, n, self._chunk):
            stop = min(n, start + self._chunk)
            k = stop - start
            gx, gy, ix, iy, pixels = (
                self._gx[:k],
                self._gy[:k],
                self._ix[:k],
                self._iy[:k],
                self._pixels[:k],
            )
            np.multiply(slope_x[start:stop], self._left_unit, out=gx)
            gx += base_x[start:stop]
            # Clamping x keeps an index from wrapping into the next grid row; rows need no
            # clamp because take(mode="clip") maps any flat index past either end of the
            # grid onto its grass margin.
            np.clip(gx, 0, grid_w - 1, out=gx)
            ix[...] = gx
            np.multiply(slope_y[start:stop], self._left_unit, out=gy)
            gy += base_y[start:stop]
            # Truncation is floor here except on (-1, 0), which lands on the margin anyway.
            iy[...] = gy
            iy *= grid_w
            iy += ix
            np.take(self._texture, iy, out=pixels, mode="clip")
            out[start:stop, self.ground_row :] = pixels
        return out


def camera_space(spec: CameraSpec | None = None) -> gym.spaces.Box:
    """Observation space of one frame, channel-last (H, W, 1) as SB3's CnnPolicy expects."""
    spec = spec or CameraSpec()
    return gym.spaces.Box(0, 255, shape=(spec.height, spec.width, 1), dtype=np.uint8)


def channels_last(frames: UInt8Array) -> UInt8Array:
    """(N, H, W) frames from `Camera.render` as an (N, H, W, 1) view for `camera_space`."""
    return frames[..., np.newaxis]


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

    Rays are marched through the raster's signed border distance (cheap, good to about a
    cell) until they cross a border or come within a couple of cells of one; there each is
    intersected exactly with the few border segments around that spot. The rare ray that
    only grazes past a border is then followed on exact geometry alone.
    """

    def __init__(self, track: Track, spec: LidarSpec | None = None) -> None:
        self.spec = spec or LidarSpec()
        self.track = track
        self.raster = TrackRaster.for_track(track)
        self.angles = np.radians(self.spec.angles_deg)
        raster = self.raster
        # In cells: positions, steps and distances then share one unit.
        self._field = (raster.signed_distance / np.float32(raster.resolution)).ravel()
        self._segment_of_cell = raster.border_segment.ravel()
        self._limit = np.float32(self.spec.max_range / raster.resolution)
        window = np.arange(-_EXACT_NEIGHBOURS, _EXACT_NEIGHBOURS + 1)
        within = (np.arange(len(raster.segment_start)) - raster.ring_start)[:, None] + window
        self._candidates = raster.ring_start[:, None] + np.mod(within, raster.ring_size[:, None])
        vector = raster.segment_vector
        self._inv_length_sq = 1.0 / np.maximum(np.sum(vector * vector, axis=1), 1e-18)

    def scan(self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> Float32Array:
        """(N, rays) float32 distances in metres, clipped to [min_range, max_range]."""
        xs, ys, yaws = _poses(x, y, yaw)
        n, count = len(xs), len(self.angles)
        res = self.raster.resolution
        theta = (yaws[:, None] + self.angles[None, :]).ravel()
        cos, sin = np.cos(theta), np.sin(theta)
        car = np.repeat(np.arange(n), count)
        col0 = ((xs - self.raster.origin[0]) / res).astype(np.float32)
        row0 = ((ys - self.raster.origin[1]) / res).astype(np.float32)
        start = self._sample(col0, row0)
        # Measure everything as seen from the car's side of the border: a car off the road
        # looks for the crossing onto it, one on the road for the crossing off it.
        on_road = start > 0
        close = np.abs(start) < _NEAR_CELLS
        if close.any():
            # Within a cell or two of a border the nearest cell may lie on the other side.
            on_road[close] = self.track.on_road(np.stack([xs[close], ys[close]], axis=1))
        side = np.where(on_road, np.float32(1.0), np.float32(-1.0)).astype(np.float32)
        rays = _Rays(
            ids=np.arange(n * count),
            col=col0[car],
            row=row0[car],
            dx=cos.astype(np.float32),
            dy=sin.astype(np.float32),
            side=side[car],
            t=np.zeros(n * count, dtype=np.float32),
            g=np.abs(start)[car],
            omega=np.full(n * count, _RELAXATION, dtype=np.float32),
        )
        geometry = _RayGeometry(xs[car], ys[car], cos, sin, side[car])
        hit = np.full(n * count, self.spec.max_range, dtype=np.float64)
        for _ in range(_ROUNDS):
            stops = self._march(rays)
            exact = self._intersect(
                geometry, stops.ids, stops.probe * res, stops.clear * res, stops.upper * res
            )
            found = np.isfinite(exact)
            hit[stops.ids[found]] = exact[found]
            missed = ~found
            rays = self._follow_exactly(
                geometry,
                stops.ids[missed],
                stops.probe[missed] * res,
                stops.clear[missed] * res,
                hit,
            )
            if not len(rays.ids):
                break
        # Rays still undecided after all rounds read max_range, as escaped ones do.
        result = hit.reshape(n, count).astype(np.float32)
        np.clip(result, self.spec.min_range, self.spec.max_range, out=result)
        return result

    def _march(self, rays: _Rays) -> _Stops:
        """Sphere-trace every ray until it crosses a border, nears one or leaves the range.

        Rays that leave the range drop out (they read max_range); the others come back as
        stops: where to look for the border, and how far along the ray is known clear.
        """
        stops: list[_Stops] = []
        for _ in range(_MAX_ITERATIONS):
            if not len(rays.ids):
                break
            step = np.maximum(rays.omega * rays.g, np.float32(_MIN_STEP_CELLS))
            t_next = rays.t + step
            g_next = rays.side * self._sample(
                rays.col + rays.dx * t_next, rays.row + rays.dy * t_next
            )
            # An over-relaxed step is safe only while the free discs around both ends cover
            # it; otherwise a thin strip could hide between them. Retry it unrelaxed.
            failed = (rays.omega > 1.0) & (rays.g + np.abs(g_next) < step)
            ok = ~failed
            crossed = ok & (g_next <= 0)
            near = ok & ~crossed & (g_next < _NEAR_CELLS)
            finished = crossed | near | (ok & (t_next >= self._limit))
            if crossed.any():
                before, after = rays.g[crossed], g_next[crossed]
                span = np.maximum(before - after, np.float32(1e-6))
                probe = rays.t[crossed] + step[crossed] * before / span
                stops.append(
                    _Stops(
                        rays.ids[crossed],
                        rays.t[crossed],
                        probe,
                        t_next[crossed] + np.float32(_WINDOW_CELLS),
                    )
                )
            if near.any():
                upper = np.full(int(near.sum()), np.inf, dtype=np.float32)
                stops.append(_Stops(rays.ids[near], rays.t[near], t_next[near], upper))
            rays.t = np.where(ok, t_next, rays.t)
            rays.g = np.where(ok, g_next, rays.g)
            rays.omega[failed] = 1.0
            if finished.any():
                rays = rays.kept(~finished)
        if len(rays.ids):
            # Out of iterations: a ray creeping up on a border at a grazing angle.
            upper = np.full(len(rays.ids), np.inf, dtype=np.float32)
            stops.append(_Stops(rays.ids, rays.t, rays.t, upper))
        return _Stops.joined(stops)

    def _follow_exactly(
        self,
        geometry: _RayGeometry,
        ids: NDArray[np.intp],
        start_m: NDArray[Any],
        clear_m: NDArray[Any],
        hit: NDArray[np.float64],
    ) -> _Rays:
        """Sphere-trace on exact distances to the segments nearby, for rays that came close
        to a border without meeting the segments there (grazing past it, or starting next
        to it): within a cell or two of a border the raster's cell-sized errors could turn
        such a miss into a hit. Rays that get clear of the border go back to marching."""
        res = self.raster.resolution
        # The first probe re-tests from where marching knew the ray clear.
        t = np.asarray(start_m, dtype=np.float64)
        checked = np.asarray(clear_m, dtype=np.float64)
        resumed: list[NDArray[np.intp]] = []
        resumed_t: list[NDArray[np.float64]] = []
        resumed_g: list[NDArray[np.float64]] = []
        # Each step covers at least _EXACT_SLACK, so this many always reach max_range.
        for _ in range(int(np.ceil(self.spec.max_range / _EXACT_SLACK)) + 1):
            if not len(ids):
                break
            exact, distance = self._intersect(
                geometry, ids, t, checked, np.full(len(ids), np.inf), with_distance=True
            )
            found = np.isfinite(exact)
            hit[ids[found]] = exact[found]
            clear = ~found & (distance > _RESUME_CELLS * res)
            if clear.any():
                resumed.append(ids[clear])
                resumed_t.append(t[clear])
                resumed_g.append(distance[clear])
            # Nothing crosses within `distance`, so only the last _EXACT_SLACK of a step
            # is unproven: the next probe, that close to it, tests it.
            checked = t
            t = t + distance + _EXACT_SLACK
            going = ~found & ~clear & (checked < self.spec.max_range)
            ids, t, checked = ids[going], t[going], checked[going]
        if not resumed:
            return _Rays.empty()
        back = np.concatenate(resumed)
        return _Rays(
            ids=back,
            col=((geometry.x[back] - self.raster.origin[0]) / res).astype(np.float32),
            row=((geometry.y[back] - self.raster.origin[1]) / res).astype(np.float32),
            dx=geometry.cos[back].astype(np.float32),
            dy=geometry.sin[back].astype(np.float32),
            side=geometry.side[back],
            t=(np.concatenate(resumed_t) / res).astype(np.float32),
            g=(np.concatenate(resumed_g) / res).astype(np.float32),
            omega=np.full(len(back), _RELAXATION, dtype=np.float32),
        )

    @overload
    def _intersect(
        self,
        geometry: _RayGeometry,
        ids: NDArray[np.intp],
        probe_m: NDArray[Any],
        lo_m: NDArray[Any],
        hi_m: NDArray[Any],
        with_distance: Literal[False] = False,
    ) -> NDArray[np.float64]: ...

    @overload
    def _intersect(
        self,
        geometry: _RayGeometry,
        ids: NDArray[np.intp],
        probe_m: NDArray[Any],
        lo_m: NDArray[Any],
        hi_m: NDArray[Any],
        with_distance: Literal[True],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

    def _intersect(
        self,
        geometry: _RayGeometry,
        ids: NDArray[np.intp],
        probe_m: NDArray[Any],
        lo_m: NDArray[Any],
        hi_m: NDArray[Any],
        with_distance: bool = False,
    ) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Nearest exact crossing in [lo, hi] metres of each ray with the border segments
        around the point `probe` metres along it (inf where none); optionally also that
        point's distance to those segments."""
        ox, oy = geometry.x[ids], geometry.y[ids]
        cos, sin = geometry.cos[ids][:, None], geometry.sin[ids][:, None]
        px = ox + probe_m * cos[:, 0]
        py = oy + probe_m * sin[:, 0]
        rows, cols = self.raster.cell_of(np.stack([px, py], axis=1))
        segments = self._candidates[self._segment_of_cell[rows * self.raster.width + cols]]
        start = self.raster.segment_start[segments]
        vector = self.raster.segment_vector[segments]
        wx, wy = start[..., 0] - ox[:, None], start[..., 1] - oy[:, None]
        vx, vy = vector[..., 0], vector[..., 1]
        # Solve origin + t * direction = start + u * vector with 2-D cross products.
        denom = cos * vy - sin * vx
        parallel = np.abs(denom) < 1e-12
        safe = np.where(parallel, 1.0, denom)
        t = (wx * vy - wy * vx) / safe
        u = (wx * sin - wy * cos) / safe
        valid = (
            ~parallel
            & (u >= -1e-9)
            & (u <= 1.0 + 1e-9)
            & (t >= np.asarray(lo_m)[:, None] - 1e-9)
            & (t <= np.asarray(hi_m)[:, None])
        )
        crossing = np.asarray(np.where(valid, t, np.inf).min(axis=1), dtype=np.float64)
        if not with_distance:
            return crossing
        # Distance from the probe point to each segment: project, clamp, measure.
        rx, ry = px[:, None] - start[..., 0], py[:, None] - start[..., 1]
        along = np.clip((rx * vx + ry * vy) * self._inv_length_sq[segments], 0.0, 1.0)
        distance = np.hypot(rx - along * vx, ry - along * vy).min(axis=1)
        return crossing, np.asarray(distance, dtype=np.float64)

    def _sample(self, col: Float32Array, row: Float32Array) -> Float32Array:
        """Signed distance (cells) of the cells under grid positions, clamped to the grid."""
        cols = np.clip(col, 0, self.raster.width - 1).astype(np.int32)
        rows = np.clip(row, 0, self.raster.height - 1).astype(np.int32)
        rows *= self.raster.width
        rows += cols
        return np.asarray(self._field.take(rows), dtype=np.float32)


@dataclass
class _RayGeometry:
    """Each ray's origin (metres) and direction, in float64 for the exact intersections."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    cos: NDArray[np.float64]
    sin: NDArray[np.float64]
    side: Float32Array  # +1 where the car is on the road, -1 off it


@dataclass
class _Stops:
    """Where marching stopped rays (in cells along each): known clear up to `clear`; look
    for the border around `probe`; accept crossings up to `upper`."""

    ids: NDArray[np.intp]
    clear: Float32Array
    probe: Float32Array
    upper: Float32Array

    @staticmethod
    def joined(parts: list[_Stops]) -> _Stops:
        if not parts:
            nothing = np.zeros(0, dtype=np.float32)
            return _Stops(np.zeros(0, dtype=np.intp), nothing, nothing, nothing)
        return _Stops(
            np.concatenate([p.ids for p in parts]),
            np.concatenate([p.clear for p in parts]),
            np.concatenate([p.probe for p in parts]),
            np.concatenate([p.upper for p in parts]),
        )


@dataclass
class _Rays:
    """The rays still marching, compacted: finished rays drop out so later steps are cheap."""

    ids: NDArray[np.intp]
    col: Float32Array
    row: Float32Array
    dx: Float32Array
    dy: Float32Array
    side: Float32Array
    t: Float32Array
    g: Float32Array
    omega: Float32Array

    @staticmethod
    def empty() -> _Rays:
        nothing = np.zeros(0, dtype=np.float32)
        return _Rays(np.zeros(0, dtype=np.intp), *([nothing] * 8))

    def kept(self, mask: NDArray[np.bool_]) -> _Rays:
        return _Rays(
            self.ids[mask],
            self.col[mask],
            self.row[mask],
            self.dx[mask],
            self.dy[mask],
            self.side[mask],
            self.t[mask],
            self.g[mask],
            self.omega[mask],
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
    return (nearest < threshold).astype(np.float32)


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


def _poses(
    x: ArrayLike, y: ArrayLike, yaw: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    xs = np.atleast_1d(np.asarray(x, dtype=np.float64))
    ys = np.atleast_1d(np.asarray(y, dtype=np.float64))
    yaws = np.atleast_1d(np.asarray(yaw, dtype=np.float64))
    if not xs.shape == ys.shape == yaws.shape or xs.ndim != 1:
        raise ValueError("x, y and yaw must be 1-D arrays of the same length (one per car)")
    return xs, ys, yaws

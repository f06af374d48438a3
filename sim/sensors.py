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
from typing import Any

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

# Sphere tracing: over-relaxed steps (checked, see `Lidar.scan`) reach grazing hits in
# fewer iterations; the iteration cap bounds the cost of a scan.
_RELAXATION = 1.6
_TRACE_ITERATIONS = 16
_REFINE_ITERATIONS = 2
# Minimum step in raster cells: the field is only exact to about a cell, so smaller
# steps near a border would stall instead of crossing it.
_MIN_STEP_CELLS = 1.0


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
            raise ValueError(f"camera field of view {self.fov_deg} must be between 0 and 180 degrees")
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
    """Distances from each car's centre to the first border line along each ray."""

    def __init__(self, track: Track, spec: LidarSpec | None = None) -> None:
        self.spec = spec or LidarSpec()
        self.raster = TrackRaster.for_track(track)
        self.angles = np.radians(self.spec.angles_deg)
        res = self.raster.resolution
        # In cells: positions, steps and distances then share one unit.
        self._field = (self.raster.signed_distance / np.float32(res)).astype(np.float32).ravel()
        self._max_cells = np.float32(self.spec.max_range / res)

    def scan(self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> Float32Array:
        """(N, rays) float32 distances in metres, clipped to [min_range, max_range]."""
        xs, ys, yaws = _poses(x, y, yaw)
        res = self.raster.resolution
        col0 = ((xs - self.raster.origin[0]) / res).astype(np.float32)[:, None]
        row0 = ((ys - self.raster.origin[1]) / res).astype(np.float32)[:, None]
        theta = yaws[:, None] + self.angles[None, :]
        dx = np.cos(theta).astype(np.float32)
        dy = np.sin(theta).astype(np.float32)
        start = self._sample(col0, row0)
        # Measure everything as seen from the car's side of the border: a car off the road
        # looks for the crossing onto it, one on the road for the crossing off it.
        side = np.where(start < 0, np.float32(-1.0), np.float32(1.0)).astype(np.float32)

        def distance_at(t: Float32Array) -> Float32Array:
            return side * self._sample(col0 + dx * t, row0 + dy * t)

        shape = theta.shape
        limit = self._max_cells
        t = np.zeros(shape, dtype=np.float32)
        g = np.broadcast_to(np.abs(start), shape).astype(np.float32)
        t_prev, g_prev = t.copy(), g.copy()
        omega = np.full(shape, _RELAXATION, dtype=np.float32)
        hit = np.full(shape, limit, dtype=np.float32)
        lo_t, lo_g = t.copy(), g.copy()
        hi_t, hi_g = t.copy(), g.copy()
        bracketed = np.zeros(shape, dtype=bool)
        active = np.ones(shape, dtype=bool)
        for _ in range(_TRACE_ITERATIONS):
            step = np.maximum(omega * g, np.float32(_MIN_STEP_CELLS))
            t_next = t + step
            g_next = distance_at(t_next)
            # Over-relaxed steps are safe only while the free discs around both ends cover
            # the step; otherwise a thin strip could hide between them. Retry unrelaxed.
            failed = (omega > 1.0) & (g + np.abs(g_next) < step) & active
            omega[failed] = 1.0
            accepted = active & ~failed
            crossed = accepted & (g_next <= 0)
            lo_t[crossed], lo_g[crossed] = t[crossed], g[crossed]
            hi_t[crossed], hi_g[crossed] = t_next[crossed], g_next[crossed]
            bracketed |= crossed
            moved = accepted & ~crossed
            t_prev[moved], g_prev[moved] = t[moved], g[moved]
            t[moved], g[moved] = t_next[moved], g_next[moved]
            active &= ~crossed & ~(moved & (t_next >= limit))
            if not active.any():
                break

        hit = self._refine(bracketed, lo_t, lo_g, hi_t, hi_g, distance_at, hit)
        if active.any():
            # Still converging on a grazing hit: a border is locally straight, so the
            # distance falls linearly along the ray; extrapolate to where it reaches zero.
            slope = (g - g_prev) / np.maximum(t - t_prev, np.float32(1e-6))
            guess = np.where(slope < 0, t - g / np.minimum(slope, np.float32(-1e-6)), limit)
            hit = np.where(active, guess, hit).astype(np.float32)
        result = hit * np.float32(res)
        np.clip(result, self.spec.min_range, self.spec.max_range, out=result)
        return result

    def _refine(
        self,
        bracketed: NDArray[np.bool_],
        lo_t: Float32Array,
        lo_g: Float32Array,
        hi_t: Float32Array,
        hi_g: Float32Array,
        distance_at: Any,
        hit: Float32Array,
    ) -> Float32Array:
        """Regula falsi inside each crossing bracket (lo on the car's side, hi across)."""

        def secant() -> Float32Array:
            span = np.maximum(lo_g - hi_g, np.float32(1e-6))
            return (lo_t + (hi_t - lo_t) * lo_g / span).astype(np.float32)

        if not bracketed.any():
            return hit
        for _ in range(_REFINE_ITERATIONS):
            mid = secant()
            g_mid = distance_at(mid)
            same_side = bracketed & (g_mid > 0)
            other_side = bracketed & ~same_side
            lo_t[same_side], lo_g[same_side] = mid[same_side], g_mid[same_side]
            hi_t[other_side], hi_g[other_side] = mid[other_side], g_mid[other_side]
        return np.where(bracketed, secant(), hit).astype(np.float32)

    def _sample(self, col: Float32Array, row: Float32Array) -> Float32Array:
        """Signed distance (cells) of the cells under grid positions, clamped to the grid."""
        cols = np.clip(col, 0, self.raster.width - 1).astype(np.int32)
        rows = np.clip(row, 0, self.raster.height - 1).astype(np.int32)
        rows *= self.raster.width
        rows += cols
        return np.asarray(self._field.take(rows), dtype=np.float32)


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

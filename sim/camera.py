"""DeepRacer's front camera for N cars at once: a pinhole over a flat ground, walls around.

For a pitched camera without roll every image row below the horizon sees one line across
the ground at a fixed distance ahead, so the ground point of pixel (row r, column c) in
the car's frame is (forward[r], lateral[r, c]); per call only the car's rotation and
translation are applied before gathering cells of the track raster's texture (what the
camera sees there is `sim.camera_scene`). Above the horizon each column sees the wall it
faces, up to the wall's top, and the background over it.

Poses are (x, y, yaw): body centre in metres, yaw in radians counter-clockwise from +x.
A camera keeps scratch buffers, so use one per thread.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim import camera_scene as scene
from sim.raster import TrackRaster
from sim.track import Track

UInt8Array = NDArray[np.uint8]
Float32Array = NDArray[np.float32]

# DeepRacer's simulated front camera, from aws-deepracer-community/deepracer-simapp:
# `bundle/urdf/deepracer/racecar.gazebo` (horizontal_fov 1.13 rad over 640x480, which
# `bundle/markov/sensors/sensors_rollout.py` resizes to 160x120) and
# `bundle/markov/cameras/frustum.py` (horizontal_fov 1.13, camera_pitch 0.2618, and the
# camera 0.14529 m ahead of and 0.13033 m above base_link in simapp v3's physics: the
# chain base_link -> chassis -> zed_camera_joint (pitched 0.2618) -> camera_joint of
# `bundle/urdf/deepracer/deepracer_single_cam.urdf`). base_link lies midway between the
# axles, as racer-tui's body centre does, and 3 mm below the ground the wheels stand on
# (wheel centres 0.039 m above it, `meshes/deepracer/*_wheel.STL` 0.036 m in radius).
DEEPRACER_FOV_RAD = 1.13
DEEPRACER_PITCH_RAD = 0.2618
DEEPRACER_MOUNT_FORWARD = 0.1453
DEEPRACER_MOUNT_HEIGHT = 0.1273

# Pixels gathered per chunk: about 8 DeepRacer frames, enough that numpy's per-call costs
# stop mattering (more does not help; fewer costs up to a third more time).
_CHUNK_PIXELS = 120_000
# Fewer cars than this are rendered all columns at once: for them numpy's per-call costs
# outweigh the work that pairing saves.
_FEW_CARS = 4
# Near the car neighbouring columns see ground closer together than the texture's cells
# are wide. Where they are at most this far apart (in cells) each pair of columns shares
# the sample at its midpoint: no pixel moves by more than a sixth of a cell (1.7 mm), and
# those rows cost half as much.
_PAIR_SPACING = 1.0 / 3.0


@dataclass(frozen=True)
class CameraSpec:
    """A front camera: greyscale frame size, horizontal field of view, where it sits on the
    car and how far it looks down. The defaults are DeepRacer's simulated camera."""

    width: int = 160
    height: int = 120
    fov_deg: float = math.degrees(DEEPRACER_FOV_RAD)  # horizontal, about 64.7
    mount_forward: float = DEEPRACER_MOUNT_FORWARD  # metres ahead of the body centre
    mount_height: float = DEEPRACER_MOUNT_HEIGHT  # metres above the ground
    pitch_deg: float = math.degrees(DEEPRACER_PITCH_RAD)  # down, 15.0

    def __post_init__(self) -> None:
        if self.width < 1 or self.height < 1:
            raise ValueError(f"camera size {self.width}x{self.height} must be at least 1x1")
        if not 0.0 < self.fov_deg < 180.0:
            raise ValueError(
                f"camera field of view {self.fov_deg} must be between 0 and 180 degrees"
            )
        if not 0.0 < self.mount_height < scene.WALL_HEIGHT:
            raise ValueError(
                "the camera must be mounted above the ground and below the walls' top "
                f"(0 < mount_height < {scene.WALL_HEIGHT} m)"
            )


DEEPRACER_CAMERA = CameraSpec()
# The physical car's lens is far wider (AWS lists a 120-degree wide-angle lens); the mount
# is racer-tui's earlier estimate. A sim-to-real option, never the simulator's default.
PHYSICAL_CAR_CAMERA = CameraSpec(
    fov_deg=120.0, mount_forward=0.12, mount_height=0.10, pitch_deg=15.0
)


class _Band:
    """Image rows gathered alike: their ground points in the car's frame are
    `forward[row]` ahead and `lateral[row, column]` to the left (cells), for the columns
    sampled; in `paired` rows each sample fills two columns. Holds scratch arrays."""

    def __init__(self, rows: slice, first: int, lateral: Float32Array, *, paired: bool) -> None:
        self.rows = rows  # image rows
        self.first = first  # index of its first row among the ground rows
        self.lateral = np.ascontiguousarray(lateral)
        self.paired = paired
        self.resize(1)

    def resize(self, chunk: int) -> None:
        shape = (chunk, 2, *self.lateral.shape)  # x and y side by side
        self.scratch = np.empty(shape, dtype=np.float32)
        self.cells = np.empty(shape, dtype=np.int32)


class Camera:
    """Renders what each car's front camera sees, (N, H, W) uint8, from the track raster.

    Below the horizon every pixel looks at the ground: the raster's texture, or where that
    lies past the walls, the wall in front of it. Above the horizon it is wall up to the
    wall's top and background over it. Walls are worked out per image column, along the
    column's bearing at the horizon (a wall's corner edge comes out upright, where a
    pitched camera slants it by a pixel or two).
    """

    def __init__(self, track: Track, spec: CameraSpec | None = None) -> None:
        self.spec = spec = spec or CameraSpec()
        self.raster = raster = TrackRaster.for_track(track)
        width, height = spec.width, spec.height
        focal = (width / 2) / math.tan(math.radians(spec.fov_deg) / 2)
        pitch = math.radians(spec.pitch_deg)
        cos_p, sin_p = math.cos(pitch), math.sin(pitch)
        # Pixel centres relative to the principal point, in units of the focal length.
        down = (np.arange(height) + 0.5 - height / 2) / focal
        right = (np.arange(width) + 0.5 - width / 2) / focal
        # A ray through image row `down` descends at this rate per unit along it.
        descent = sin_p + down * cos_p
        with np.errstate(divide="ignore"):
            scale = np.where(descent > 0, spec.mount_height / descent, np.inf)
        forward = scale * (cos_p - down * sin_p)
        # From inside the field no ground farther than its diagonal lies before the walls:
        # rows looking farther see wall only.
        x0, y0, x1, y1 = raster.field
        self._rise = scene.WALL_HEIGHT - spec.mount_height  # camera to the walls' top
        ground = (descent > 0) & (forward <= math.hypot(x1 - x0, y1 - y0))
        self.horizon_row = int(np.count_nonzero(descent <= 0))  # first row below the horizon
        self.ground_row = ground_row = height - int(np.count_nonzero(ground))
        res = raster.resolution
        rows = slice(ground_row, height)
        self._forward = ((forward[rows] + spec.mount_forward) / res).astype(np.float32)
        left = np.broadcast_to(-right, (height, width)).copy()
        spacing = scale / (focal * res)  # cells between neighbouring columns' ground points
        paired = (spacing <= _PAIR_SPACING) & (width % 2 == 0)
        pair_row = max(ground_row, height - int(np.count_nonzero(paired)))
        if pair_row < height:
            pairs = (left[0, 0::2] + left[0, 1::2]) / 2
            left[pair_row:, 0::2] = left[pair_row:, 1::2] = pairs
        lateral = (scale[rows, None] * left[rows] / res).astype(np.float32)
        split = pair_row - ground_row
        # Few cars: one band of all columns (pairs computed twice, the same way). Many
        # cars: the paired rows once per pair.
        self._whole = [_Band(rows, 0, lateral, paired=False)]
        self._split = [
            band
            for band in (
                _Band(slice(ground_row, pair_row), 0, lateral[:split], paired=False),
                _Band(slice(pair_row, height), split, lateral[split:, 0::2], paired=True),
            )
            if band.lateral.size
        ]
        # Farthest ground point of each rendered row from the camera, as negative numbers
        # rising down the image: rows that do not reach the nearest wall see no wall.
        reach = np.hypot(forward[rows], scale[rows] * np.abs(right).max())
        self._reach_descending = (-reach).tolist()
        # Each texture row runs on into `pad` cells past the walls, the next row's left
        # margin too: from inside the field a ground point overshoots a row by less than
        # that, so it cannot wrap into the field of another row. take(mode="clip") maps
        # flat indices past either end of the grid onto past-the-walls cells as well.
        farthest = float(reach.max()) if len(reach) else 0.0
        pad = math.ceil((farthest + spec.mount_forward) / res) + 2
        texture = np.pad(raster.texture, ((0, 0), (0, pad)), constant_values=scene.BEYOND_WALLS)
        self._stride = texture.shape[1]
        self._texture = texture.ravel()
        # Walls: each column's bearing at the horizon as a unit vector in the car's frame
        # (there a ray runs (1/cos p, -right) ahead and left), and how steeply each pixel
        # above the horizon looks up.
        bearing = np.stack([np.ones(width), -right * cos_p])
        self._bearing_ahead, self._bearing_left = bearing / np.hypot(bearing[0], bearing[1])
        # Rows between the horizon and the first ground row look down: never over a wall.
        up = -(sin_p + down[:ground_row, None] * cos_p)
        level = np.hypot(cos_p - down[:ground_row, None] * sin_p, right[None, :])
        self._tan_elevation = np.where(up > 0, up / level, -np.inf).astype(np.float32)
        sampled = sum(band.lateral.size for band in self._split)
        self._chunk = max(1, _CHUNK_PIXELS // max(1, sampled))
        for band in self._split:
            band.resize(self._chunk)

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of one frame."""
        return self.spec.height, self.spec.width

    def render(
        self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike, out: UInt8Array | None = None
    ) -> UInt8Array:
        """Frames for N poses, (N, H, W) uint8; pass `out` to reuse an output array."""
        table = _pose_table(x, y, yaw)
        n = table.shape[1]
        height, width = self.shape
        if out is None:
            out = np.empty((n, height, width), dtype=np.uint8)
        elif out.shape != (n, height, width) or out.dtype != np.uint8:
            raise ValueError(f"out must be a uint8 array of shape {(n, height, width)}")
        if n == 0:
            return out
        terms = self._car_terms(table)
        wall_tone, wall_top = self._walls(terms[:, _AHEAD], terms[:, _LEFT])
        nearest_wall = terms[:, _NEAREST]
        # Above the ground rows: the wall, or the background over its top.
        above = out[:, : self.ground_row]
        above[...] = wall_tone[:, None, :]
        np.copyto(above, _BACKGROUND, where=self._tan_elevation >= wall_top[:, None, :])

        # Per car and ground row: where the row's centre lies (cells), and how its lateral
        # offsets turn into x and y (float32 is ample: a ten-thousandth of a cell).
        single = terms.astype(np.float32)
        base = single[:, _TRIG, None] * self._forward
        base += single[:, _CELLS, None]
        turn = single[:, _TURN, None, None]
        bands, chunk = (self._whole, n) if n < _FEW_CARS else (self._split, self._chunk)
        for start in range(0, n, chunk):
            stop = min(n, start + chunk)
            nearest = min(nearest_wall[start:stop].tolist())  # cheaper than numpy's min
            for band in bands:
                frames = out[start:stop, band.rows]
                sampled = frames[:, :, 0::2] if band.paired else frames
                rows = slice(band.first, band.first + band.lateral.shape[0])
                self._gather(band, base[start:stop, :, rows], turn[start:stop], sampled, nearest)
                if band.paired:
                    frames[:, :, 1::2] = sampled
            # Ground past the walls shows the wall in front of it; only rows reaching as
            # far as the nearest wall can.
            far_rows = bisect.bisect_right(self._reach_descending, -nearest)
            if far_rows:
                far = out[start:stop, self.ground_row : self.ground_row + far_rows]
                # BEYOND_WALLS is 0 and every ground tone is brighter than any wall.
                np.maximum(far, wall_tone[start:stop, None, :], out=far)
        return out

    def _gather(
        self,
        band: _Band,
        base: Float32Array,
        turn: Float32Array,
        frames: UInt8Array,
        nearest_wall: float,
    ) -> None:
        """Texture cells under one chunk's sampled pixels of a band, into `frames`."""
        k = len(base)
        if len(band.cells) < k:
            band.resize(k)
        scratch, cells = band.scratch[:k], band.cells[:k]
        np.multiply(turn, band.lateral, out=scratch)
        # Truncating to int32 is floor here except on (-1, 0), which lands on the grid's
        # outer ring anyway. Adding straight into the int32 array does the same float32
        # sum as adding in place and then converting: quicker for many cars, slower for
        # a few.
        if band.paired or k >= _FEW_CARS:
            np.add(scratch, base[..., None], out=cells, casting="unsafe")
        else:
            scratch += base[..., None]
            cells[...] = scratch
        ix, iy = cells[:, 0], cells[:, 1]
        if nearest_wall < 0:
            # A camera outside the field can look any distance past a row's end.
            np.clip(ix, 0, self.raster.width - 1, out=ix)
        iy *= self._stride
        iy += ix
        # take() wants int64 indices and converts int32 ones on the fly, which still beats
        # doing the index arithmetic in int64.
        self._texture.take(iy, out=frames, mode="clip")

    def _car_terms(self, table: NDArray[np.float64]) -> NDArray[np.float64]:
        """(N, 15) per-car numbers the frame is made from, in the columns named below:
        the yaw's cosine and sine, (-sin, cos), the position in cells, for each wall the
        factors a and b (see `_walls`), and the camera's distance to the nearest wall
        (negative outside the field).

        For a few cars they are worked out with Python floats, which costs a fraction of
        numpy's per-call overhead; both ways do the same IEEE operations in the same
        order, so a car's frame does not depend on how many cars are rendered with it.
        """
        trig = np.cos(table[2, :, None] - _QUARTER_TURN)  # cos, sin
        mount, rise = self.spec.mount_forward, self._rise
        x0, y0, x1, y1 = self.raster.field
        ox, oy = self.raster.origin
        res = self.raster.resolution
        if table.shape[1] < _FEW_CARS:
            rows = []
            for x, y, (c, s) in zip(
                table[0].tolist(), table[1].tolist(), trig.tolist(), strict=True
            ):
                cx, cy = x + mount * c, y + mount * s
                gap = (cx - x0, cy - y0, x1 - cx, y1 - cy)
                s0, s1, s2, s3 = [rise / max(g, 1e-9) for g in gap]
                rows.append(
                    (
                        *(c, s, -s, c),
                        *((x - ox) / res, (y - oy) / res),
                        *((-c) * s0, (-s) * s1, c * s2, s * s3),
                        *(s * s0, (-c) * s1, (-s) * s2, c * s3),
                        min(gap),
                    )
                )
            return np.array(rows)
        position = table[:2].T
        camera = position + mount * trig
        # Low x, low y, high x, high y, as in _WALL_TONES.
        gaps = np.concatenate([camera - (x0, y0), (x1, y1) - camera], axis=1)
        steep = rise / np.maximum(gaps, 1e-9)
        return np.concatenate(
            [
                trig,
                trig[:, ::-1] * (-1.0, 1.0),
                (position - (ox, oy)) / res,
                trig[:, [0, 1, 0, 1]] * (-1.0, -1.0, 1.0, 1.0) * steep,
                trig[:, [1, 0, 1, 0]] * (1.0, -1.0, -1.0, 1.0) * steep,
                gaps.min(axis=1, keepdims=True),
            ],
            axis=1,
        )

    def _walls(
        self, ahead: NDArray[np.float64], left: NDArray[np.float64]
    ) -> tuple[UInt8Array, Float32Array]:
        """Per car and column, the tone of the wall the column looks at and the tangent of
        the elevation of that wall's top.

        Along a bearing b a wall at distance g (perpendicular) with outward normal m is
        g / (b . m) away, so its top rises at (wall height - camera height) * (b . m) / g:
        the wall met first is the one whose top rises steepest. With the column's bearing
        as (ahead, left) in the car's frame that is ahead * a + left * b, a and b per car
        and wall (`_car_terms`): all four walls are a few broadcast products. A camera
        outside the field is up against the walls it has passed."""
        rise = ahead[:, :, None] * self._bearing_ahead
        rise += left[:, :, None] * self._bearing_left
        wall = rise.argmax(axis=1)
        return _WALL_TONES[wall], rise.max(axis=1).astype(np.float32)


_BACKGROUND = np.uint8(scene.BACKGROUND)
_WALL_TONES = np.array(
    [scene.WALL_LOW_X, scene.WALL_LOW_Y, scene.WALL_HIGH_X, scene.WALL_HIGH_Y], dtype=np.uint8
)
# cos(yaw - these) = (cos yaw, sin yaw) in one call.
_QUARTER_TURN = np.array([0.0, math.pi / 2])
# Columns of `Camera._car_terms`. Per wall (low x, low y, high x, high y) the factors of
# the bearing's ahead and left parts are a = (-cos, -sin, cos, sin) and
# b = (sin, -cos, -sin, cos), times how steeply that wall's top rises per unit of them.
_TRIG = slice(0, 2)
_TURN = slice(2, 4)  # (-sin, cos): how a lateral offset turns into x and y
_CELLS = slice(4, 6)
_AHEAD = slice(6, 10)
_LEFT = slice(10, 14)
_NEAREST = 14


def camera_space(spec: CameraSpec | None = None) -> gym.spaces.Box:
    """Observation space of one frame, channel-last (H, W, 1) as SB3's CnnPolicy expects."""
    spec = spec or CameraSpec()
    return gym.spaces.Box(0, 255, shape=(spec.height, spec.width, 1), dtype=np.uint8)


def channels_last(frames: UInt8Array) -> UInt8Array:
    """(N, H, W) frames from `Camera.render` as an (N, H, W, 1) view for `camera_space`."""
    return frames[..., np.newaxis]


def poses(
    x: ArrayLike, y: ArrayLike, yaw: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Car poses as three float64 arrays of one row per car; refuses anything else."""
    table = _pose_table(x, y, yaw)
    return table[0], table[1], table[2]


def _pose_table(x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> NDArray[np.float64]:
    """(3, N) float64: x, y and yaw of N cars, checked."""
    try:
        table = np.array([x, y, yaw], dtype=np.float64)
    except ValueError:
        table = np.empty(0)  # ragged: refused below
    if table.ndim == 1 and len(table) == 3:
        table = table[:, None]
    if table.ndim != 2:
        raise ValueError("x, y and yaw must be 1-D arrays of the same length (one per car)")
    # A sum is finite only if every term is (or the poses are absurdly far out).
    if not math.isfinite(float(table.sum())):
        raise ValueError("a car pose holds NaN or infinity; sensors need finite x, y and yaw")
    return table

"""DeepRacer's front camera for N cars at once: a pinhole over a flat ground, walls around.

For a pitched camera without roll every image row below the horizon sees one line across
the ground at a fixed distance ahead, so the ground point of pixel (row r, column c) in
the car's frame is (forward[r], lateral[r, c]); per call only the car's rotation and
translation are applied before gathering cells of the track raster's texture (what the
camera sees there is `sim.sensors.camera_scene`). Above the horizon each column sees the wall it
faces, up to the wall's top, and the background over it. Solid objects on the track
(`Solids`: DeepRacer's boxes, head-to-bot's bot cars) are drawn last, over the ground and
the walls, as upright boxes through the same pinhole.

Poses are (x, y, yaw): body centre in metres, yaw in radians counter-clockwise from +x.
A camera keeps scratch buffers, so use one per thread.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import gymnasium as gym
import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.foundation.plural import counted
from sim.sensors import camera_scene as scene
from sim.sensors.raster import TrackRaster
from sim.tracks.track import Track

UInt8Array = NDArray[np.uint8]
Float32Array = NDArray[np.float32]

# DeepRacer's simulated front camera, from aws-deepracer-community/deepracer-simapp:
# `bundle/urdf/deepracer/racecar.gazebo` (horizontal_fov 1.13 rad over 640x480, which
# `bundle/markov/sensors/sensors_rollout.py` resizes to 160x120) and
# `bundle/markov/cameras/frustum.py` (horizontal_fov 1.13, camera_pitch 0.2618, and the
# camera 0.14529 m ahead of and 0.13033 m above base_link: the chain base_link -> chassis
# -> zed_camera_joint (pitched 0.2618) -> camera_joint of
# `bundle/urdf/deepracer/deepracer_single_cam.urdf`, which every simapp since version 3
# spawns, `deepracer_kinematics` included).
DEEPRACER_FOV_RAD = 1.13
_URDF_PITCH_RAD = 0.2618
_URDF_CAMERA = (0.14529, 0.13033)  # (ahead, up) of base_link, in the chassis' frame
# The car stands on its wheels, and the URDF does not hold its chassis level: the rear
# axle is 0.038999 m above base_link (base_link_joint 0.023249 + rear wheel joints
# 0.01575) at 0.081663 m behind it, the front axle 0.035008 m above it (steering hinges
# 0.011759) at 0.082311 m ahead, and all four wheels are 0.036 m in radius
# (`meshes/deepracer/*_wheel.STL`). Resting on flat ground the chassis is tipped nose-up
# by atan(0.003991 / 0.163974), 1.39 degrees, so the camera looks that much less far
# down than its joint's 0.2618 and sits a little higher. DeepRacer's own frames show it:
# fitting a pinhole camera to the centre-line dashes of deepracer-utils' `dr-demo-1.png`
# (dashes 0.0508 m long every 0.1016 m, from `meshes/reinvent/reinvent_base.dae`) gives
# a pitch of 0.2373 rad.
_REAR_AXLE = (-0.081663, 0.038999)  # (ahead, up) of base_link
_FRONT_AXLE = (0.082311, 0.035008)
_WHEEL_RADIUS = 0.036


def _resting_mount() -> tuple[float, float, float]:
    """(ahead of the body centre, above the ground, pitch down in radians) of DeepRacer's
    camera on a car at rest on flat ground. racer-tui's body centre is the point of the
    ground midway between the axles, as base_link is midway between them in the URDF."""
    (rear_x, rear_z), (front_x, front_z) = _REAR_AXLE, _FRONT_AXLE
    tilt = math.atan2(rear_z - front_z, front_x - rear_x)  # nose up
    # The ground line through both wheels' contact points, in the chassis' frame.
    ground_x, ground_z = (rear_x + front_x) / 2, (rear_z + front_z) / 2 - _WHEEL_RADIUS
    along = (math.cos(tilt), -math.sin(tilt))  # the ground's direction, ahead
    up = (math.sin(tilt), math.cos(tilt))  # and its normal
    dx, dz = _URDF_CAMERA[0] - ground_x, _URDF_CAMERA[1] - ground_z
    return dx * along[0] + dz * along[1], dx * up[0] + dz * up[1], _URDF_PITCH_RAD - tilt


# About 0.1418 m ahead, 0.1328 m up, 0.2375 rad (13.6 degrees) down.
DEEPRACER_MOUNT_FORWARD, DEEPRACER_MOUNT_HEIGHT, DEEPRACER_PITCH_RAD = _resting_mount()

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
    pitch_deg: float = math.degrees(DEEPRACER_PITCH_RAD)  # down, about 13.6

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


@dataclass(frozen=True)
class Solids:
    """Solid objects standing on the track, each car its own k of them (DeepRacer's boxes,
    head-to-bot's bot cars): upright boxes from the ground up to `height`.

    `x`, `y` (metres, the footprint's centre) and `heading` (radians counter-clockwise
    from +x, the direction of `length`) are (n_cars, k) float arrays: row i holds car i's
    objects. `length`, `width`, `height` (metres) and the grey levels of the sides and of
    the top are (k,) arrays, one per object. Arrays are checked and converted to float64
    and uint8 on construction; what the camera needs of them is worked out on first use
    and kept, so objects that stay put can be drawn frame after frame from one Solids.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    heading: NDArray[np.float64]
    length: NDArray[np.float64]
    width: NDArray[np.float64]
    height: NDArray[np.float64]
    side_tone: NDArray[np.uint8]
    top_tone: NDArray[np.uint8]

    def __post_init__(self) -> None:
        places = [np.asarray(getattr(self, name), dtype=np.float64) for name in _PLACES]
        sizes = [np.asarray(getattr(self, name), dtype=np.float64) for name in _SIZES]
        tones = [np.asarray(getattr(self, name)) for name in _TONES]
        shape = places[0].shape
        if len(shape) != 2 or any(a.shape != shape for a in places):
            raise ValueError("solids' x, y and heading must be 2-D arrays (n_cars, k) alike")
        k = shape[1]
        if any(a.shape != (k,) for a in sizes + tones):
            raise ValueError(
                f"solids' length, width, height and tones must be 1-D arrays of {k} values "
                "(one per object)"
            )
        if not math.isfinite(float(sum(a.sum() for a in places))):
            raise ValueError("a solid's place holds NaN or infinity")
        if not all(bool((np.isfinite(a) & (a > 0)).all()) for a in sizes):
            raise ValueError("solids' length, width and height must be positive metres")
        for name, tone in zip(_TONES, tones, strict=True):
            if tone.dtype != np.uint8:
                if not np.issubdtype(tone.dtype, np.integer) or (
                    tone.size and not 0 <= tone.min() <= tone.max() <= 255
                ):
                    raise ValueError(f"solids' {name} must be grey levels, whole numbers 0-255")
                object.__setattr__(self, name, tone.astype(np.uint8))
        for name, array in zip(_PLACES, places, strict=True):
            object.__setattr__(self, name, array)
        for name, array in zip(_SIZES, sizes, strict=True):
            object.__setattr__(self, name, array)

    def placed_at(self, x: ArrayLike, y: ArrayLike, heading: ArrayLike) -> Solids:
        """The same objects standing elsewhere (arrays shaped as `x`): a race's moving cars
        are drawn anew every frame, and only their places need checking."""
        x, y, heading = (np.asarray(a, dtype=np.float64) for a in (x, y, heading))
        if not (x.shape == y.shape == heading.shape == self.x.shape):
            raise ValueError("solids' x, y and heading must keep their (n_cars, k) shape")
        if not math.isfinite(float(x.sum() + y.sum() + heading.sum())):
            raise ValueError("a solid's place holds NaN or infinity")
        moved = object.__new__(Solids)
        fields = {**self.__dict__, "x": x, "y": y, "heading": heading}
        fields.pop("_spheres", None)
        fields.pop("_boxes", None)
        moved.__dict__.update(fields)
        return moved

    @property
    def cars(self) -> int:
        """How many cars the objects are laid out for (rows of `x`)."""
        return int(self.x.shape[0])

    @functools.cached_property
    def _spheres(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Each object's bounding sphere: its middle (n_cars, 4, k) as homogeneous world
        coordinates (x, y, z, 1), and its radius (k,)."""
        n, k = self.x.shape
        middle = np.empty((n, 4, k))
        middle[:, 0], middle[:, 1], middle[:, 2], middle[:, 3] = self.x, self.y, self.height / 2, 1
        return middle, self._radius

    # What depends on the sizes alone is kept when the solids move (`placed_at`).
    @functools.cached_property
    def _radius(self) -> NDArray[np.float64]:
        radius: NDArray[np.float64] = np.sqrt(self.length**2 + self.width**2 + self.height**2) / 2
        return radius

    @functools.cached_property
    def _half(self) -> NDArray[np.float64]:
        half = np.empty((len(self.length), 2))
        half[:, 0], half[:, 1] = self.length, self.width
        return half / 2

    @functools.cached_property
    def _boxes(self) -> _Boxes:
        """The objects' corners, footprints and axes in world coordinates."""
        n, k = self.x.shape
        half = self._half
        cos, sin = np.cos(self.heading), np.sin(self.heading)
        axes = np.empty((n, k, 2, 2))  # along the length (cos, sin), across it (-sin, cos)
        axes[..., 0, 0], axes[..., 0, 1], axes[..., 1, 0], axes[..., 1, 1] = cos, sin, -sin, cos
        centre = np.empty((n, k, 2))
        centre[..., 0], centre[..., 1] = self.x, self.y
        # From the centre half the length along, half the width across, and up.
        reach = (axes * half[:, :, None])[..., None]  # (n, k, 2, 2, 1)
        corners = np.ones((n, k, 4, 8))
        corners[:, :, :2] = centre[..., None] + reach[:, :, 0] * _CORNERS[:, 1]
        corners[:, :, :2] += reach[:, :, 1] * _CORNERS[:, 2]
        corners[:, :, 2] = self.height[:, None] * _CORNERS[:, 3]
        return _Boxes(corners, centre, axes, half)


class _Boxes(NamedTuple):
    """Solids as the camera draws them, in world coordinates, for n cars' k objects."""

    corners: NDArray[np.float64]  # (n, k, 4, 8): homogeneous (x, y, z, 1), as in _CORNERS
    centre: NDArray[np.float64]  # (n, k, 2): the footprint's centre
    axes: NDArray[np.float64]  # (n, k, 2, 2): unit vectors along the length, and across
    half: NDArray[np.float64]  # (k, 2): half the length, half the width


_PLACES = ("x", "y", "heading")
_SIZES = ("length", "width", "height")
_TONES = ("side_tone", "top_tone")


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
        # Any larger pad gives the same frames: cameras of one track whose pads round up
        # alike share one padded texture (camera randomisation builds many of them).
        self._texture, self._stride = _padded_texture(raster, -(-pad // _PAD_STEP) * _PAD_STEP)
        # Walls: each column's bearing at the horizon as a unit vector in the car's frame
        # (there a ray runs (1/cos p, -right) ahead and left), and how steeply each pixel
        # above the horizon looks up.
        bearing = np.stack([np.ones(width), -right * cos_p])
        self._bearing_ahead, self._bearing_left = bearing / np.hypot(bearing[0], bearing[1])
        # Rows between the horizon and the first ground row look down: never over a wall.
        up = -(sin_p + down[:ground_row, None] * cos_p)
        level = np.hypot(cos_p - down[:ground_row, None] * sin_p, right[None, :])
        self._tan_elevation = np.where(up > 0, up / level, -np.inf).astype(np.float32)
        # Solids: a point (ahead, left, up) in metres from the lens, in the car's frame, goes
        # to homogeneous pixel coordinates (X, Y, Z) = this matrix times it: it lies at depth
        # Z along the optical axis and shows at column X / Z and row Y / Z (pixel edges at
        # whole numbers, as above).
        self._project = np.array(
            [
                [width / 2 * cos_p, -focal, -width / 2 * sin_p],
                [height / 2 * cos_p - focal * sin_p, 0.0, -height / 2 * sin_p - focal * cos_p],
                [cos_p, 0.0, -sin_p],
            ]
        )
        # X, width Z - X and Z, which are negative for a point left of the image, right of
        # it or behind the lens, scaled to its distance from that side of the frustum.
        sides = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, width], [0.0, 0.0, 1.0]])
        self._frustum_sides = sides / np.linalg.norm(sides @ self._project, axis=1)[:, None]
        # The same distances straight from a point (ahead, left, up) of the lens, as plain
        # floats for `sees_none`.
        self._side_rows = (self._frustum_sides @ self._project).tolist()
        self._frustum_rows: list[list[float]] = self._frustum_sides.tolist()
        # Turning world (x, y) by the car's yaw, then projecting: the cosine's part and the
        # sine's (ahead = x cos + y sin, left = y cos - x sin).
        self._turn_cos = self._project[:, :2]
        self._turn_sin = self._project[:, 1::-1] * _FLIP
        self._lens_drop = -spec.mount_height * self._project[:, 2]  # the lens above the ground
        # The same numbers per projection row as plain floats (`_draw_lone_solid`): the
        # cosine's parts, the sine's, the up column and the lens's drop.
        self._projection_rows = [
            (*turn_cos, *turn_sin, up, drop)
            for turn_cos, turn_sin, up, drop in zip(
                self._turn_cos.tolist(),
                self._turn_sin.tolist(),
                self._project[:, 2].tolist(),
                self._lens_drop.tolist(),
                strict=True,
            )
        ]
        self._all_columns = np.array([0.0, width])[:, None]
        self._columns = np.arange(width)
        self._pixel_centres = self._columns + 0.5
        self._steps = np.arange(0, 0)  # one row apart down a flattened frame, grown as needed
        sampled = sum(band.lateral.size for band in self._split)
        self._chunk = max(1, _CHUNK_PIXELS // max(1, sampled))  # bands grow to it when used

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of one frame."""
        return self.spec.height, self.spec.width

    def render(
        self,
        x: ArrayLike,
        y: ArrayLike,
        yaw: ArrayLike,
        solids: Solids | None = None,
        out: UInt8Array | None = None,
    ) -> UInt8Array:
        """Frames for N poses, (N, H, W) uint8; pass `out` to reuse an output array.

        With `solids` (laid out for the same N cars) each car also sees its own objects,
        standing on the ground in front of the walls."""
        table = _pose_table(x, y, yaw)
        n = table.shape[1]
        height, width = self.shape
        if solids is not None and solids.cars != n:
            raise ValueError(f"solids are laid out for {counted(solids.cars, 'car')}, not {n}")
        if out is None:
            out = np.empty((n, height, width), dtype=np.uint8)
        elif out.shape != (n, height, width) or out.dtype != np.uint8:
            raise ValueError(f"out must be a uint8 array of shape {(n, height, width)}")
        if n == 0:
            return out
        self._render_scene(table, out)
        if solids is not None and solids.x.size:
            if out.flags.c_contiguous:
                self._draw_solids(table, solids, out)
            else:
                frames = np.ascontiguousarray(out)
                self._draw_solids(table, solids, frames)
                out[...] = frames
        return out

    def sees_none(
        self,
        x: Sequence[float],
        y: Sequence[float],
        yaw: Sequence[float],
        *,
        objects: Sequence[tuple[float, float]],
        radius: float,
        middle_height: float,
    ) -> bool:
        """True when no car at (x, y, yaw) can see any of `objects` (x, y each, the same
        for every car: spheres of `radius` whose middles stand `middle_height` above the
        ground), by a margin: then `render` would draw none of them either, and a caller
        may skip building them (a head-to-head car's rival is mostly behind or beside it).
        False whenever in doubt. Plain floats: for a car or two and an object or two, numpy
        would cost more than the test saves."""
        forward = self.spec.mount_forward
        up = middle_height - self.spec.mount_height
        reach = -(radius + _CULL_MARGIN)
        for car_x, car_y, car_yaw in zip(x, y, yaw, strict=True):
            cos, sin = math.cos(car_yaw), math.sin(car_yaw)
            lens_x, lens_y = car_x + forward * cos, car_y + forward * sin
            for object_x, object_y in objects:
                dx, dy = object_x - lens_x, object_y - lens_y
                ahead, left = dx * cos + dy * sin, dy * cos - dx * sin
                nearest = min(a * ahead + b * left + c * up for a, b, c in self._side_rows)
                if not nearest < reach:
                    return False
        return True

    def _render_scene(self, table: NDArray[np.float64], out: UInt8Array) -> None:
        """The ground, the walls and the background over them, into `out`."""
        n = table.shape[1]
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

    def _draw_solids(self, table: NDArray[np.float64], solids: Solids, out: UInt8Array) -> None:
        """Each car's solids over its frame in `out` (C-contiguous), nearest last.

        A box seen from a point outside it fills the cone from the lens over it, bounded
        by the planes through the lens and the box's outline edges (at most six, listed
        in _OUTLINES). Each plane's trace on the image is a line, and a pixel lies in the
        cone when its centre is on the inner side of every line: that holds even for
        corners behind the lens, so nothing needs clipping. In an image column each line
        bounds the rows from above or from below, so an object covers one run of rows
        per column: `_runs` works them out for all objects and columns at once.

        Only elementwise operations and matrix products per car touch the numbers, so a
        car's frame does not depend on what else is drawn with it. Numpy's calls cost more
        here than its arithmetic, hence the terse style."""
        height, width = self.shape
        k = solids.x.shape[1]
        if table.shape[1] == 1 and k == 1:  # a two-car race's rival: plain floats first
            car_x, car_y, car_yaw = table[:, 0].tolist()
            self._draw_lone_solid(car_x, car_y, car_yaw, solids, out)
            return
        # Per car, the map from homogeneous world coordinates to homogeneous pixel ones
        # (X, Y, Z: column X / Z, row Y / Z, depth Z): into the car's frame from the lens,
        # then through the lens.
        trig = np.cos(table[2, :, None] - _QUARTER_TURN)[:, :, None, None]  # cos, sin
        lens = table[:2].T + self.spec.mount_forward * trig[:, :, 0, 0]
        to_pixels = np.empty((len(lens), 3, 4))
        turned = to_pixels[:, :, :2]
        np.add(trig[:, 0] * self._turn_cos, trig[:, 1] * self._turn_sin, out=turned)
        to_pixels[:, :, 2] = self._project[:, 2]
        shift = turned[:, :, 0] * lens[:, :1] + turned[:, :, 1] * lens[:, 1:]
        np.subtract(self._lens_drop, shift, out=to_pixels[:, :, 3])
        # In view unless its bounding sphere lies wholly outside a side of the frustum.
        middle, radius = solids._spheres
        inside = np.minimum.reduce(self._frustum_sides @ (to_pixels @ middle), axis=1)
        which = (inside > -radius).ravel().nonzero()[0]
        count = len(which)
        if not count:
            return
        car, kind = which // k, which % k
        boxes = solids._boxes
        # Corner j of object v: (X, Y, Z) at corners[:, j, v].
        mapping = to_pixels[car].transpose(1, 2, 0)[:, :, None]  # (3, 4, 1, V)
        world = boxes.corners[car, kind].transpose(1, 2, 0)  # (4, 8, V), rows x, y, z, 1
        corners = mapping[:, 0] * world[0] + mapping[:, 1] * world[1]
        corners += mapping[:, 2] * world[2]
        corners += mapping[:, 3]
        # Columns each object can cover: its corners' span, or all when one lies behind.
        depth = corners[2]
        ahead = np.minimum.reduce(depth) > 0
        column = corners[0] / np.where(ahead, depth, 1.0)
        lowest, highest = np.minimum.reduce(column), np.maximum.reduce(column)
        extent = np.array([np.floor(lowest), np.ceil(highest)])
        extent = np.where(ahead, extent, self._all_columns)
        extent = np.minimum(np.maximum(extent, 0.0), width)
        span = int(np.maximum.reduce(extent[1] - extent[0]))
        if span <= 0:
            return
        first = np.minimum(extent[0], width - span).astype(np.intp)
        centres = first[:, None] + self._pixel_centres[:span]  # (V, span)
        # The lens in each object's own frame (u along its length, v across): which of its
        # sides face it, and whether it looks down on the top, pick the outline.
        half = boxes.half[kind]
        offset = lens[car] - boxes.centre[car, kind]
        axes = boxes.axes[car, kind]
        lens_uv = axes[:, :, 0] * offset[:, :1] + axes[:, :, 1] * offset[:, 1:]
        region = (lens_uv >= -half).astype(np.intp) + (lens_uv > half)
        above = self.spec.mount_height > solids.height[kind]
        outline = _OUTLINES[region @ _REGION_WEIGHTS + above].transpose(1, 2, 0)  # (2, 6, V)
        corners = corners.reshape(3, -1)  # corner j of object v at j * V + v
        mine = np.arange(count)
        start, end = _runs(corners[:, outline * count + mine], centres, height)
        if above.any():
            # Seen from above, a column's run holds the top's run, with side above and
            # below it (looking steeply past a corner shows a sliver of side over the top).
            lid_start, lid_end = _runs(corners[:, _TOP_OUTLINE * count + mine], centres, height)
            lid_start = np.where(above[:, None], np.clip(lid_start, start, end), start)
            lid_end = np.where(above[:, None], np.clip(lid_end, lid_start, end), start)
            runs = np.array([start, lid_start, lid_start, lid_end, lid_end, end])
            side, top = solids.side_tone[kind], solids.top_tone[kind]
            tones = np.array([side, top, side])
        else:
            runs, tones = np.array([start, end]), solids.side_tone[kind][None]
        # Painter's order: each car's farthest object first, an object's distance being
        # that of its footprint's nearest point from the lens. (Checked against ray
        # casting for objects half a metre or more apart; two closer together, near the
        # car, can come out in the wrong order for a few pixels along an edge.)
        order = None  # one object per car (a race's rival, mostly): none can overlap
        if count > 1 and not bool((car[1:] != car[:-1]).all()):
            gap = np.hypot(*np.maximum(np.abs(lens_uv) - half, 0.0).T)
            order = np.lexsort((-gap, car))
        self._paint(out, runs, tones, car=car, first=first, order=order)

    def _draw_lone_solid(
        self, car_x: float, car_y: float, car_yaw: float, solids: Solids, out: UInt8Array
    ) -> None:
        """`_draw_solids` for one car and one object (a two-car race's rival) in plain
        floats up to the runs: the same operations on each number in the same order, so
        the same frame to the bit (tests hold it to the batched path), without numpy's
        per-call costs on arrays of a dozen numbers. Culling alone may add up in another
        order: it only skips objects that no pixel centre can see."""
        height, width = self.shape
        # numpy's cosine and sine, as the batched path takes them: another machine's libm
        # need not round alike.
        cos, sin = np.cos(car_yaw - _QUARTER_TURN).tolist()
        lens_x = car_x + self.spec.mount_forward * cos
        lens_y = car_y + self.spec.mount_forward * sin
        to_pixels = []
        for cos_x, cos_y, sin_x, sin_y, up, drop in self._projection_rows:
            along_x, along_y = cos * cos_x + sin * sin_x, cos * cos_y + sin * sin_y
            to_pixels.append((along_x, along_y, up, drop - (along_x * lens_x + along_y * lens_y)))
        object_x, object_y = float(solids.x[0, 0]), float(solids.y[0, 0])
        object_height = float(solids.height[0])
        middle = (object_x, object_y, object_height / 2, 1.0)
        seen = [sum(a * b for a, b in zip(row, middle, strict=True)) for row in to_pixels]
        radius = float(solids._radius[0])
        for plane in self._frustum_rows:
            if sum(a * b for a, b in zip(plane, seen, strict=True)) <= -radius:
                return
        # The object's corners as `Solids._boxes` works them out, then through the lens.
        heading = solids.heading[0, 0]
        half_l, half_w = float(solids._half[0, 0]), float(solids._half[0, 1])
        axis_cos, axis_sin = np.cos(heading).item(), np.sin(heading).item()
        reach = ((axis_cos * half_l, axis_sin * half_l), (-axis_sin * half_w, axis_cos * half_w))
        pixels: list[list[float]] = [[], [], []]  # X, Y, Z of corner j
        for _, along, across, up in _CORNER_ROWS:
            x = object_x + reach[0][0] * along + reach[1][0] * across
            y = object_y + reach[0][1] * along + reach[1][1] * across
            z = object_height * up
            for row, (m_x, m_y, m_z, m_w) in zip(pixels, to_pixels, strict=True):
                row.append(m_x * x + m_y * y + m_z * z + m_w)
        depth = pixels[2]
        ahead = min(depth) > 0
        if ahead:
            columns = [column / z for column, z in zip(pixels[0], depth, strict=True)]
            low, high = float(math.floor(min(columns))), float(math.ceil(max(columns)))
        else:  # a corner behind the lens: any column may show it
            low, high = 0.0, float(width)
        low, high = min(max(low, 0.0), width), min(max(high, 0.0), width)
        span = int(high - low)
        if span <= 0:
            return
        first = int(min(low, width - span))
        centres = np.add(self._pixel_centres[:span], first, dtype=np.float64)[None, :]
        offset_x, offset_y = lens_x - object_x, lens_y - object_y
        region = 0
        for (u_x, u_y), half, weight in zip(
            ((axis_cos, axis_sin), (-axis_sin, axis_cos)), (half_l, half_w), (6, 2), strict=True
        ):
            lens_u = u_x * offset_x + u_y * offset_y
            region += ((lens_u >= -half) + (lens_u > half)) * weight
        above = self.spec.mount_height > object_height
        ends = np.array(
            [[[[row[j]] for j in edge] for edge in _OUTLINES[region + above]] for row in pixels]
        )
        start, end = _runs(ends, centres, height)
        side = solids.side_tone[:1]
        if above:
            top = np.array(
                [[[[row[j]] for j in edge] for edge in _TOP_OUTLINE[:, :, 0]] for row in pixels]
            )
            lid_start, lid_end = _runs(top, centres, height)
            lid_start = np.clip(lid_start, start, end)
            lid_end = np.clip(lid_end, lid_start, end)
            runs = np.array([start, lid_start, lid_start, lid_end, lid_end, end])
            tones = np.array([side, solids.top_tone[:1], side])
        else:
            runs, tones = np.array([start, end]), side[None]
        self._paint(out, runs, tones, car=_FIRST, first=np.array([first]), order=None)

    def _paint(
        self,
        out: UInt8Array,
        runs: NDArray[np.intp],
        tones: UInt8Array,
        *,
        car: NDArray[np.intp],
        first: NDArray[np.intp],
        order: NDArray[np.intp] | None,
    ) -> None:
        """Paints objects' runs of rows into their cars' frames, objects in `order` (by
        car, farthest first; None when no car has two objects): `runs` (2 * parts, V, span)
        holds each part's (side, or side, top, side) first and past-the-end rows per column
        of the object's window, which begins at column `first`, and `tones` (parts, V) the
        parts' tones.

        All pixels go through one flat index, in layers: the farthest object of each car,
        then the next farthest and so on (objects of one layer belong to different cars,
        so cannot overlap)."""
        height, width = self.shape
        rank = None
        if order is not None:
            cars = car[order]
            rank = np.arange(len(order)) - np.searchsorted(cars, cars)  # within its car
            by_layer = np.argsort(rank, kind="stable")
            order, rank = order[by_layer], rank[by_layer]
            runs, tones, car, first = runs[:, order], tones[:, order], car[order], first[order]
        start, stop = runs[0::2], runs[1::2]  # (parts, V, span)
        lengths = (stop - start).transpose(1, 0, 2).ravel()  # by object, part, column
        ends = np.add.accumulate(lengths)
        total = int(ends[-1])
        if not total:
            return
        # Each run's pixels, a row apart down its column of the frames flattened.
        offset = car * (height * width) + first
        origin = start.transpose(1, 0, 2) * width + (
            offset[:, None, None] + self._columns[: runs.shape[2]]
        )
        index = np.repeat(origin.ravel() - width * (ends - lengths), lengths)
        if len(self._steps) < total:
            self._steps = np.arange(0, 2 * total * width, width)
        index += self._steps[:total]
        parts = ends.reshape(len(car), -1, runs.shape[2])[:, :, -1]  # (V, parts)
        tones = tones.T
        tone = tones.flat[0]
        uniform = bool((tones == tone).all())
        if not uniform:
            values = np.repeat(tones.ravel(), np.diff(parts.ravel(), prepend=0))
        frames = out.reshape(-1)
        layers = [] if rank is None else parts[:-1, -1][np.diff(rank) > 0].tolist()
        for low, high in itertools.pairwise([0, *layers, total]):
            frames[index[low:high]] = tone if uniform else values[low:high]

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
        # maximum.reduce is what ndarray.max runs, without its Python wrapper.
        return _WALL_TONES[wall], np.maximum.reduce(rise, axis=1).astype(np.float32)


_BACKGROUND = np.uint8(scene.BACKGROUND)
_WALL_TONES = np.array(
    [scene.WALL_LOW_X, scene.WALL_LOW_Y, scene.WALL_HIGH_X, scene.WALL_HIGH_Y], dtype=np.uint8
)
# cos(yaw - these) = (cos yaw, sin yaw) in one call.
_QUARTER_TURN = np.array([0.0, math.pi / 2])
_FIRST = np.zeros(1, dtype=np.intp)  # a lone car's index
# Columns of `Camera._car_terms`. Per wall (low x, low y, high x, high y) the factors of
# the bearing's ahead and left parts are a = (-cos, -sin, cos, sin) and
# b = (sin, -cos, -sin, cos), times how steeply that wall's top rises per unit of them.
_TRIG = slice(0, 2)
_TURN = slice(2, 4)  # (-sin, cos): how a lateral offset turns into x and y
_CELLS = slice(4, 6)
_AHEAD = slice(6, 10)
_LEFT = slice(10, 14)
_NEAREST = 14

# Solids' corners as multiples of (1, half length, half width, height): the bottom four
# counter-clockwise from (+u, +v), u along the object's length and v across it, then the
# top four above them.
_FOOTPRINT = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
_CORNERS = np.array([(1.0, u, v, z) for z in (0.0, 1.0) for u, v in _FOOTPRINT])
_CORNER_ROWS: list[list[float]] = _CORNERS.tolist()


def _outline(u: int, v: int, above: bool) -> list[int]:
    """The corners (as in _CORNERS) around a box's outline seen from a lens in region
    (u, v) of its footprint (0: past its -u or -v side, 1: between the two sides, 2: past
    the + side), below or above its top: along the bottom of the sides facing the lens,
    from the lens's left to its right, then back along the top, over those sides from
    below and round the far side from above. Always six: a repeated corner adds an edge
    of no length, which bounds nothing, so a lens inside the box sees box all round."""
    if (u, v) == (1, 1):
        return [4, 5, 6, 7, 7, 7] if above else [0] * 6
    sides = {(2, 1): 3, (0, 1): 1, (1, 2): 0, (1, 0): 2}  # one side faces the lens
    meet = {(2, 2): 0, (0, 2): 1, (0, 0): 2, (2, 0): 3}  # two sides, meeting at this corner
    if (u, v) in sides:
        near = [sides[u, v], (sides[u, v] + 1) % 4]
    else:
        near = [(meet[u, v] + i) % 4 for i in (-1, 0, 1)]
    top = [(near[-1] + i) % 4 for i in range(6 - len(near))] if above else near[::-1]
    ring = near + [4 + corner for corner in top]
    return ring + ring[-1:] * (6 - len(ring))


# Outline corners and the next ones round, by region (u * 3 + v) * 2 + above.
_RINGS = np.array(
    [_outline(u, v, above) for u in range(3) for v in range(3) for above in (False, True)]
)
_OUTLINES = np.stack([_RINGS, np.roll(_RINGS, -1, axis=1)], axis=1)  # (18, 2, 6)
_TOP_OUTLINE = np.array([[4, 5, 6, 7], [5, 6, 7, 4]])[..., None]
# (x, y) to (-y, x): a quarter turn counter-clockwise.
_FLIP = np.array([-1.0, 1.0])
# Region number (u * 3 + v) * 2 from the regions along u and v.
_REGION_WEIGHTS = np.array([6, 2])


def _runs(
    ends: NDArray[np.float64], centres: NDArray[np.float64], height: int
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Per object and column, the first row and the row past the last whose pixel centre
    looks into the cone from the lens over an outline.

    `ends` (3, 2, m, V) holds the outline's edges: the X, Y, Z (homogeneous pixel
    coordinates) of each of V objects' m corners and of the next ones round, going round
    the same way as seen from the lens; `centres` (V, columns) the columns' pixel centres.
    An edge and the lens span a plane whose trace on the image is the line
    A x + B y + C = 0, (A, B, C) the cross product of the next corner and this one: the
    outlines go round so that the inside is where A x + B y + C > 0."""
    (x0, x1), (y0, y1), (z0, z1) = ends
    a = y1 * z0 - z1 * y0
    b = z1 * x0 - x1 * z0
    c = x1 * y0 - y1 * x0
    # Where B > 0 the line bounds the first row, y >= -(A x + C) / B, where B < 0 the
    # last one; an upright line (B = 0) is leant a hair, so that it still bounds the rows,
    # by -+infinity either side, and an edge of no length (A = B = C = 0) bounds nothing.
    upright = b == 0.0
    if upright.any():
        b[upright] = 1e-9 * (np.abs(a) + np.abs(c))[upright] + 1e-300
    below = b > 0
    scale = -1.0 / np.abs(b)
    # Both bounds as maxima over lines of slope * x + offset: the first row's, and the
    # last row's negated; each line takes part in one, and in the other bounds nothing.
    slope = a * scale
    offset = c * scale - (below - 0.5)  # rows' centres are at r + 0.5
    first = np.where(below, offset, -np.inf)
    last = np.where(below, -np.inf, offset)
    across = slope[..., None] * centres  # (m, V, columns)
    start = np.ceil(np.maximum.reduce(across + first[..., None]))
    start = np.minimum(np.maximum(start, 0.0), height)
    across += last[..., None]
    end = np.minimum(np.floor(-np.maximum.reduce(across)) + 1, height)
    return start.astype(np.intp), np.maximum(end, start).astype(np.intp)


# Pads are rounded up to this many cells, so that cameras of one track share textures.
_PAD_STEP = 512
_padded_textures: weakref.WeakKeyDictionary[TrackRaster, dict[int, UInt8Array]] = (
    weakref.WeakKeyDictionary()
)


def _padded_texture(raster: TrackRaster, pad: int) -> tuple[UInt8Array, int]:
    """The raster's texture with `pad` cells past the walls after every row, flattened
    (read-only, shared by every camera of the raster asking for that pad), and its stride."""
    by_pad = _padded_textures.setdefault(raster, {})
    flat = by_pad.get(pad)
    if flat is None:
        texture = np.pad(raster.texture, ((0, 0), (0, pad)), constant_values=scene.BEYOND_WALLS)
        flat = texture.ravel()
        flat.flags.writeable = False
        by_pad[pad] = flat
    return flat, raster.width + pad


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


# How far past a sphere's radius `sees_none` wants an object out of view: far above the
# rounding of the two ways of working the distance out (about 1e-14 m at 30 m).
_CULL_MARGIN = 1e-6
# `sees_none` is tried for at most this many (car, object) pairs: beyond, numpy is quicker.
CULL_PAIRS = 4


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

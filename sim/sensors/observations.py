"""What a model sees: camera, lidar, or the compact `vector` state, for N cars at once.

DeepRacer's sensor names map onto these: FRONT_FACING_CAMERA and STEREO_CAMERAS -> camera
(the stereo pair is rendered as one front camera here), LIDAR -> lidar, SECTOR_LIDAR ->
sector_lidar (8 sectors, 1 when a border is closer than 0.5 m). `vector` is privileged
state for fast training on a CPU: speed, steering, heading error, offset from the centre
line and look-ahead points of the centre line in the car's frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from sim.foundation.arrays import FloatArray
from sim.physics.simulation import TrackSimulation
from sim.sensors.batched import (
    Camera,
    CameraSpec,
    Lidar,
    LidarSpec,
    camera_space,
    lidar_space,
    sector_lidar_space,
    sectors,
)
from sim.sensors.camera import CULL_PAIRS
from sim.sensors.objects_drawn import object_solids
from sim.sensors.randomisation.render import PerturbedCamera

if TYPE_CHECKING:
    from sim.physics.objects.field import ObjectField
    from sim.sensors.randomisation.perturbation import CameraPerturbation
    from sim.sensors.randomisation.render import PerturbedCamera

# Metres ahead along the centre line at which the vector sensor reports the track.
LOOK_AHEAD_DISTANCES = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0)
_LOOK_AHEAD_SCALE = 3.0
VECTOR_SIZE = 5 + 2 * len(LOOK_AHEAD_DISTANCES)


@dataclass(frozen=True)
class SensorOptions:
    camera_width: int = 160
    camera_height: int = 120
    lidar_rays: int = 64
    lidar_range: float = 2.0


class Observer:
    """Builds batched observations of a `TrackSimulation` for the chosen sensors."""

    def __init__(
        self, sim: TrackSimulation, sensors: tuple[str, ...], options: SensorOptions | None = None
    ) -> None:
        self.sim = sim
        self.sensors = sensors
        self.options = options or SensorOptions()
        spaces: dict[str, gym.spaces.Space[Any]] = {}
        self._camera: Any = None
        self._perturbed: PerturbedCamera | None = None
        self._lidar: Any = None
        opts = self.options
        if "camera" in sensors:
            spec = CameraSpec(width=opts.camera_width, height=opts.camera_height)
            self._camera = Camera(sim.track, spec)
            spaces["camera"] = camera_space(spec)
        if "lidar" in sensors or "sector_lidar" in sensors:
            lidar_spec = LidarSpec(rays=opts.lidar_rays, max_range=opts.lidar_range)
            self._lidar = Lidar(sim.track, lidar_spec)
            if "lidar" in sensors:
                spaces["lidar"] = lidar_space(lidar_spec)
            else:
                spaces["sector_lidar"] = sector_lidar_space()
        if "vector" in sensors:
            spaces["vector"] = gym.spaces.Box(-5.0, 5.0, shape=(VECTOR_SIZE,), dtype=np.float32)
        self.spaces = spaces
        self.space: gym.spaces.Space[Any] = (
            next(iter(spaces.values())) if len(spaces) == 1 else gym.spaces.Dict(spaces)
        )

    def perturb_camera(
        self,
        cars: Sequence[int],
        perturbations: Sequence[CameraPerturbation],
        *,
        noise_seed: int | None = None,
    ) -> None:
        """From now on car `cars[i]`'s camera sees through `perturbations[i]`
        (`sim.sensors.randomisation`); the others keep theirs, the plain camera until given one.
        `noise_seed` seeds the sensor noise (on the first call only). Nothing changes for a
        model without a camera."""
        if self._camera is None:
            return
        if self._perturbed is None:
            self._perturbed = PerturbedCamera(self.sim.track, self._camera, self.sim.n, noise_seed)
        self._perturbed.set(cars, perturbations)

    @property
    def camera_perturbations(self) -> tuple[CameraPerturbation, ...] | None:
        """Each car's camera perturbation, or None while every car has the plain camera."""
        return None if self._perturbed is None else self._perturbed.perturbations

    def _out_of_view(self, objects: ObjectField, x: Any, y: Any, yaw: Any) -> bool:
        """No car's camera can see any of its objects: a frame without them is the same
        frame (`Camera.sees_none`), built and drawn for nothing. Tried only for a car or
        two with an object or two each, the same for every car (a head-to-head race), and
        the plain camera."""
        camera = self._camera
        if camera is None or self._perturbed is not None:
            return False
        if len(x) * objects.count > CULL_PAIRS or len(objects.x) != 1:
            return False
        shape = objects.shape
        radius = math.sqrt(shape.length**2 + shape.width**2 + shape.height**2) / 2
        spots = list(zip(objects.x[0].tolist(), objects.y[0].tolist(), strict=True))
        unseen = camera.sees_none(
            x.tolist(),
            y.tolist(),
            yaw.tolist(),
            objects=spots,
            radius=radius,
            middle_height=shape.height / 2,
        )
        return bool(unseen)

    def observe(self, cars: Sequence[int] | None = None) -> Any:
        """Observations for all N cars, or for `cars` only (rows in that order): an
        (N, ...) array, or a dict of them."""
        parts: dict[str, np.ndarray] = {}
        fleet = self.sim.fleet
        pick: Any = slice(None) if cars is None else np.asarray(cars, dtype=np.intp)
        x, y, yaw = fleet.x[pick], fleet.y[pick], fleet.yaw[pick]
        if self._camera is not None:
            objects = self.sim.objects  # each car's own boxes or bot cars, drawn in its view
            solids = (
                None
                if objects is None or self._out_of_view(objects, x, y, yaw)
                else object_solids(objects, np.arange(self.sim.n)[pick])
            )
            if self._perturbed is None:
                frames = self._camera.render(x, y, yaw, solids=solids)
            else:  # camera randomisation: each car through its own camera
                which = np.arange(self.sim.n)[pick]
                frames = self._perturbed.render(which, x, y, yaw, solids=solids)
            parts["camera"] = frames[..., None]
        if self._lidar is not None:
            scan = self._lidar.scan(x, y, yaw)
            objects = self.sim.objects
            if objects is not None:  # the lidar sees each car's own objects and the borders
                which = np.arange(self.sim.n)[pick]
                spec = self._lidar.spec
                seen = objects.ray_distances(
                    which, x, y, yaw, angles=self._lidar.angles, max_range=spec.max_range
                )
                scan = np.clip(np.minimum(scan, seen), spec.min_range, spec.max_range)
                scan = scan.astype(np.float32)
            if "lidar" in self.spaces:
                parts["lidar"] = scan
            else:
                parts["sector_lidar"] = sectors(scan)
        if "vector" in self.spaces:
            parts["vector"] = vector_state(self.sim)[pick]
        if len(parts) == 1:
            return next(iter(parts.values()))
        return parts


def vector_state(sim: TrackSimulation) -> np.ndarray:
    """The compact `vector` observation, (N, VECTOR_SIZE) float32."""
    if sim.n == 1:
        return _vector_state_one(sim)
    fleet = sim.fleet
    spec = fleet.spec
    centre = sim.track.centerline
    tangent = sim.driving_tangents()
    ahead_s = sim.s[:, None] + np.asarray(LOOK_AHEAD_DISTANCES)[None, :]
    if sim.any_reversed:  # cars driving the other way round look the other way
        sign = sim.direction_sign[:, None]
        ahead_s = sim.s[:, None] + sign * np.asarray(LOOK_AHEAD_DISTANCES)[None, :]
    cos_yaw, sin_yaw = np.cos(fleet.yaw), np.sin(fleet.yaw)
    # Heading error as sine and cosine: continuous across +-180 degrees.
    sin_err = cos_yaw * tangent[:, 1] - sin_yaw * tangent[:, 0]
    cos_err = cos_yaw * tangent[:, 0] + sin_yaw * tangent[:, 1]
    half_width = np.maximum(sim.track_width / 2.0, 1e-6)
    offset = np.where(sim.left_of_center, 1.0, -1.0) * sim.distance_from_center / half_width
    points: FloatArray = centre.point_at(ahead_s)
    dx = points[..., 0] - fleet.x[:, None]
    dy = points[..., 1] - fleet.y[:, None]
    forward = (dx * cos_yaw[:, None] + dy * sin_yaw[:, None]) / _LOOK_AHEAD_SCALE
    left = (-dx * sin_yaw[:, None] + dy * cos_yaw[:, None]) / _LOOK_AHEAD_SCALE
    out = np.empty((sim.n, VECTOR_SIZE), dtype=np.float32)
    out[:, 0] = fleet.speed / spec.max_speed
    out[:, 1] = fleet.steering / np.radians(spec.max_steering_deg)
    out[:, 2] = sin_err
    out[:, 3] = cos_err
    out[:, 4] = offset
    out[:, 5::2] = forward
    out[:, 6::2] = left
    np.clip(out, -5.0, 5.0, out=out)
    return out


def _vector_state_one(sim: TrackSimulation) -> np.ndarray:
    """`vector_state` for a lone car (a race) in plain floats: the same arithmetic, without
    numpy's per-call overhead on length-1 arrays."""
    fleet = sim.fleet
    spec = fleet.spec
    centre = sim.centre_projector
    s = float(sim.s[0])
    x, y, yaw = float(fleet.x[0]), float(fleet.y[0]), float(fleet.yaw[0])
    way = float(sim.direction_sign[0])
    if way > 0.0:
        tangent_x, tangent_y = centre.direction_at(s)
    else:  # turned round (alternate direction): rare enough for the numpy path
        tangent_x, tangent_y = (float(v) for v in sim.driving_tangents()[0])
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    half_width = max(float(sim.track_width[0]) / 2.0, 1e-6)
    side = 1.0 if sim.left_of_center[0] else -1.0
    values = [
        float(fleet.speed[0]) / spec.max_speed,
        float(fleet.steering[0]) / math.radians(spec.max_steering_deg),
        cos_yaw * tangent_y - sin_yaw * tangent_x,
        cos_yaw * tangent_x + sin_yaw * tangent_y,
        side * float(sim.distance_from_center[0]) / half_width,
    ]
    for distance in LOOK_AHEAD_DISTANCES:
        px, py = centre.point_at(s + way * distance)
        dx, dy = px - x, py - y
        values.append((dx * cos_yaw + dy * sin_yaw) / _LOOK_AHEAD_SCALE)
        values.append((-dx * sin_yaw + dy * cos_yaw) / _LOOK_AHEAD_SCALE)
    # Clipped before the float32 rounding, which cannot cross +-5 (both are float32s).
    return np.array([[min(max(value, -5.0), 5.0) for value in values]], dtype=np.float32)

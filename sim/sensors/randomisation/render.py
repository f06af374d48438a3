"""Each car's frames through its own camera perturbation.

A car's pose jitter is a camera of its own geometry (the model's `CameraSpec` moved up and
tilted), built on first use and kept: cars drawn the same height and pitch share it, and
every camera of a track shares one texture (`sim.sensors.camera`). Light, colours, blur and noise
are applied to the rendered frames (`sim.sensors.randomisation.frames`). A car whose perturbation is
`PLAIN` gets exactly the plain camera's frame.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.sensors.camera import Camera, Solids, UInt8Array
from sim.sensors.randomisation.frames import Float32Array, SensorNoise, perturb_frames, tone_table
from sim.sensors.randomisation.perturbation import PLAIN, CameraPerturbation
from sim.tracks.track import Track

# Cameras of other geometries kept at once (pose strength 1 draws 9 heights x 13 pitches;
# a camera holds a few hundred kB besides its track's shared texture).
MAX_CAMERAS = 128


class PerturbedCamera:
    """Renders N cars' frames, each through the perturbation set for it (PLAIN at first).

    `camera` is the model's camera on `track`; `seed` seeds the sensor noise. One object
    per thread, as for `Camera`."""

    def __init__(self, track: Track, camera: Camera, cars: int, seed: int | None = None) -> None:
        self.track = track
        self.camera = camera
        self._perturbations: list[CameraPerturbation] = [PLAIN] * cars
        self._tables: list[Float32Array | None] = [None] * cars
        self._cameras: OrderedDict[tuple[float, float], Camera] = OrderedDict()
        height, width = camera.shape
        self._noise = SensorNoise(height, width, np.random.default_rng(seed))

    @property
    def perturbations(self) -> tuple[CameraPerturbation, ...]:
        return tuple(self._perturbations)

    def set(self, cars: Sequence[int], perturbations: Sequence[CameraPerturbation]) -> None:
        """From now on car `cars[i]` sees through `perturbations[i]`."""
        if len(cars) != len(perturbations):
            raise ValueError("give one camera perturbation per car")
        for car, perturbation in zip(cars, perturbations, strict=True):
            self._perturbations[car] = perturbation
            self._tables[car] = None

    def camera_for(self, perturbation: CameraPerturbation) -> Camera:
        """The camera of the model's geometry moved by the perturbation's pose."""
        if not perturbation.moves_camera:
            return self.camera
        key = (perturbation.height_m, perturbation.pitch_deg)
        camera = self._cameras.get(key)
        if camera is None:
            spec = self.camera.spec
            moved = replace(
                spec,
                mount_height=spec.mount_height + perturbation.height_m,
                pitch_deg=spec.pitch_deg + perturbation.pitch_deg,
            )
            camera = Camera(self.track, moved)
            self._cameras[key] = camera
            while len(self._cameras) > MAX_CAMERAS:
                self._cameras.popitem(last=False)
        else:
            self._cameras.move_to_end(key)
        return camera

    def render(
        self,
        cars: NDArray[np.intp],
        x: ArrayLike,
        y: ArrayLike,
        yaw: ArrayLike,
        solids: Solids | None = None,
    ) -> UInt8Array:
        """Frames (n, H, W) of cars `cars` (ids, in row order) at poses (x, y, yaw)."""
        chosen = [self._perturbations[car] for car in cars.tolist()]
        if not any(p.changes_frames for p in chosen):
            return self.camera.render(x, y, yaw, solids=solids)
        xs, ys, yaws = (np.asarray(a, dtype=np.float64).reshape(-1) for a in (x, y, yaw))
        groups: dict[int, list[int]] = {}
        cameras: dict[int, Camera] = {}
        for row, perturbation in enumerate(chosen):
            camera = self.camera_for(perturbation)
            groups.setdefault(id(camera), []).append(row)
            cameras[id(camera)] = camera
        if len(groups) == 1:
            frames = next(iter(cameras.values())).render(xs, ys, yaws, solids=solids)
        else:
            height, width = self.camera.shape
            frames = np.empty((len(chosen), height, width), dtype=np.uint8)
            for key, rows in groups.items():
                pick = np.asarray(rows, dtype=np.intp)
                part = None if solids is None else _solids_of(solids, pick)
                frames[pick] = cameras[key].render(xs[pick], ys[pick], yaws[pick], solids=part)
        touched = [row for row, p in enumerate(chosen) if p.changes_tones or p.noise or p.blur]
        if touched:
            pick = np.asarray(touched, dtype=np.intp)
            tables = [self._table(int(cars[row])) for row in touched]
            changed = frames[pick]
            perturb_frames(changed, [chosen[row] for row in touched], self._noise, tables)
            frames[pick] = changed
        return frames

    def _table(self, car: int) -> Float32Array:
        table = self._tables[car]
        if table is None:
            table = self._tables[car] = tone_table(self._perturbations[car])
        return table


def _solids_of(solids: Solids, rows: NDArray[np.intp]) -> Solids:
    """The objects of some of the cars `solids` is laid out for."""
    return Solids(
        x=solids.x[rows],
        y=solids.y[rows],
        heading=solids.heading[rows],
        length=solids.length,
        width=solids.width,
        height=solids.height,
        side_tone=solids.side_tone,
        top_tone=solids.top_tone,
    )

"""A car archive as a race `Driver`: it drives racer-tui's car from racer-tui's camera.

Each step renders every car's front camera (`sim.sensors.batched.Camera`, uint8 0..255, the range
the car's own camera gives its graph) at the size the graph's input asks for, runs the
graph once for all cars and applies each car's action. It fits wherever a `Driver` does:
`run_trials`, `evaluate_model(..., driver=...)` and the race engine.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import torch

from sim.car_archive.archive import CarArchive
from sim.car_archive.policy import CarPolicy
from sim.physics.car import car_for_simapp_version
from sim.physics.simulation import TrackSimulation
from sim.race.driver import DriverAction
from sim.sensors.batched import Camera, CameraSpec
from sim.tracks.track import Track


class CarArchiveDriver:
    """Drives with a DeepRacer car archive's policy; deterministic (the car's argmax).

    `car` is the car DeepRacer's simulator would drive this model in, by the version in its
    `model_metadata.json` (older models run on simapp's slower-steering car): pass it to
    `run_trials` or the simulation for a like-for-like drive.
    """

    def __init__(
        self,
        archive: CarArchive,
        camera: CameraSpec | None = None,
        *,
        name: str | None = None,
        content_hash: str | None = None,
    ) -> None:
        """`name` and `content_hash` default to the archive's own (a garage model that
        drives with the archive passes its name and hash, as races record them)."""
        # One frame per car is too small a batch to share between cores (as PolicyDriver).
        torch.set_num_threads(1)
        self.policy = CarPolicy(archive)
        self.name = name or archive.name
        self.content_hash = content_hash or f"car-archive:{archive.content_hash}"
        self._space = archive.metadata.action_space
        self.car = car_for_simapp_version(archive.metadata.simapp_version)
        # The camera's own defaults (DeepRacer's), at the frame size the graph takes.
        self.camera_spec = replace(
            camera or CameraSpec(), width=self.policy.width, height=self.policy.height
        )
        self._camera: Camera | None = None
        self._track: Track | None = None

    def reset(self, sim: TrackSimulation) -> None:
        if self._camera is None or self._track is not sim.track:
            self._camera = Camera(sim.track, self.camera_spec)
            self._track = sim.track

    def frames(self, sim: TrackSimulation) -> np.ndarray:
        """What each car's camera sees now, (N, H, W) uint8."""
        if self._camera is None or self._track is not sim.track:
            self.reset(sim)
        assert self._camera is not None
        fleet = sim.fleet
        return self._camera.render(fleet.x, fleet.y, fleet.yaw)

    def act(self, sim: TrackSimulation) -> DriverAction:
        actions = self.policy.actions(self.frames(sim))
        steering, speed = self._space.targets(actions)
        if self._space.kind == "discrete":
            index = np.asarray(actions, dtype=np.int64)
        else:
            index = np.full(sim.n, -1, dtype=np.int64)
        return DriverAction(
            steering_deg=np.asarray(steering, dtype=np.float64),
            speed=np.asarray(speed, dtype=np.float64),
            action_index=index,
        )

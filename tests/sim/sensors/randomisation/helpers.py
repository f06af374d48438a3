"""What the tests of camera randomisation share."""

from __future__ import annotations

import numpy as np

from sim.physics.simulation import TrackSimulation
from sim.sensors.camera import Camera

CARS = 6


def plain_frames(camera: Camera, sim: TrackSimulation) -> np.ndarray:
    """What the plain camera shows every car of `sim`, (N, H, W)."""
    fleet = sim.fleet
    return camera.render(fleet.x, fleet.y, fleet.yaw)

"""Fixtures for camera randomisation: re:Invent 2018 and cars standing on it."""

from __future__ import annotations

import numpy as np
import pytest

from sim.env import EnvConfig
from sim.physics.simulation import TrackSimulation
from sim.sensors.camera import Camera
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track
from tests.sim.sensors.randomisation.helpers import CARS


@pytest.fixture(scope="module")
def reinvent() -> Track:
    return resolve_track("reinvent_base")


@pytest.fixture(scope="module")
def camera(reinvent: Track) -> Camera:
    return Camera(reinvent)


@pytest.fixture
def sim(reinvent: Track) -> TrackSimulation:
    """CARS cars spread round the track on the centre line, at their episodes' start."""
    simulation = EnvConfig(track=reinvent, sensors=("camera",)).simulation(CARS)
    starts = np.linspace(0.0, reinvent.length, CARS, endpoint=False).tolist()
    simulation.reset_cars(range(CARS), starts)
    return simulation

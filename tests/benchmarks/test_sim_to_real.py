"""The sim-to-real proxy's pictures and the driver that evaluates through them."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from benchmarks.sim.perturbed_driver import perturbed_driver
from benchmarks.sim.sim_to_real import CONDITIONS
from sim.garage.options import new_model
from sim.physics.simulation import TrackSimulation
from sim.sensors import camera_scene as scene
from sim.sensors.camera import Camera
from sim.sensors.observations import Observer
from sim.sensors.randomisation.perturbation import PLAIN, CameraPerturbation, draw_perturbation
from sim.sensors.randomisation.settings import CameraRandomisation
from sim.training.evaluation import run_trials
from sim.training.policy import build_network, save_policy
from sim.training.policy_driver import driver_for_model


def test_the_benchmarks_pictures_lie_outside_what_training_draws() -> None:
    rng = np.random.default_rng(0)
    draws = [draw_perturbation(CameraRandomisation(), rng) for _ in range(2000)]
    assert CONDITIONS["plain"] == PLAIN
    assert CONDITIONS["darker"].gain < min(d.gain for d in draws)
    assert CONDITIONS["noisier"].noise > max(d.noise for d in draws)
    assert CONDITIONS["pitch +5 deg"].pitch_deg > max(d.pitch_deg for d in draws)
    lines = CONDITIONS["line colours"].palette
    assert lines.border < min(d.palette.border for d in draws)
    assert lines.centre > max(d.palette.centre for d in draws)
    assert (lines.road, lines.grass) == (scene.ROAD, scene.GRASS)


def test_a_perturbed_driver_drives_through_its_picture(monkeypatch: pytest.MonkeyPatch) -> None:
    folder = new_model("camera", sensors=["FRONT_FACING_CAMERA"])
    torch.manual_seed(0)
    save_policy(folder.policy_file, build_network(folder.metadata()))
    track = folder.track()
    plain = run_trials(driver_for_model(folder), track, 2, max_seconds=3.0)
    # Through the plain picture it drives exactly as the model's own driver.
    assert run_trials(perturbed_driver(folder, PLAIN), track, 2, max_seconds=3.0) == plain
    # Through another picture, what it looks at is that picture.
    driver = perturbed_driver(folder, CameraPerturbation(gain=0.5))
    assert driver.name == "camera" and driver.content_hash == folder.content_hash()
    looked_at: list[np.ndarray] = []
    observe = Observer.observe

    def observing(self: Observer, cars: Any = None) -> Any:
        obs = observe(self, cars)
        looked_at.append(np.array(obs)[..., 0])
        return obs

    monkeypatch.setattr(Observer, "observe", observing)
    sim = TrackSimulation(track, 1)
    sim.reset_cars([0], [0.0])
    driver.reset(sim)
    driver.act(sim)
    frame = Camera(track).render(sim.fleet.x, sim.fleet.y, sim.fleet.yaw).astype(float)
    assert len(looked_at) == 1
    assert np.abs(looked_at[0] - 0.5 * frame).max() <= 0.5 + 1e-3

"""A camera model trained with randomisation sees perturbed frames; its evaluations do not."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from sim.garage.options import new_model
from sim.sensors.camera import Camera
from sim.sensors.observations import Observer
from sim.sensors.randomisation.perturbation import CameraPerturbation
from sim.sensors.randomisation.settings import CameraRandomisation
from sim.tracks.track import Track
from sim.training import events
from sim.training.trainer import RunOptions, Trainer

TINY = RunOptions(minutes=5, cars=4, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)


class Seen:
    """Every camera frame an observer hands out, with the poses and the perturbations."""

    def __init__(self) -> None:
        self.frames: list[
            tuple[tuple[CameraPerturbation, ...] | None, Track, np.ndarray, np.ndarray]
        ] = []

    def record(self, observer: Observer, cars: Any, obs: Any) -> None:
        if "camera" not in observer.sensors:
            return
        pick = slice(None) if cars is None else np.asarray(cars, dtype=np.intp)
        fleet = observer.sim.fleet
        poses = np.stack([fleet.x[pick], fleet.y[pick], fleet.yaw[pick]])
        which = np.arange(observer.sim.n)[pick]
        cameras = observer.camera_perturbations
        chosen = None if cameras is None else tuple(cameras[i] for i in which.tolist())
        frames = np.array(obs["camera"] if isinstance(obs, dict) else obs)[..., 0]
        self.frames.append((chosen, observer.sim.track, poses, frames))


@pytest.fixture
def seen(monkeypatch: pytest.MonkeyPatch) -> Seen:
    record = Seen()
    observe = Observer.observe

    def observing(self: Observer, cars: Any = None) -> Any:
        obs = observe(self, cars)
        record.record(self, cars, obs)
        return obs

    monkeypatch.setattr(Observer, "observe", observing)
    return record


def test_a_short_training_run_renders_perturbed_frames(seen: Seen) -> None:
    folder = new_model(
        "real-world", sensors=["FRONT_FACING_CAMERA"], camera_randomisation=CameraRandomisation()
    )
    stream: list[events.Event] = []

    def stop() -> bool:
        return any(isinstance(event, events.Update) for event in stream)

    ended = Trainer(folder, stream.append, stop, TINY).run()
    assert ended.kind == "stopped" and folder.has_policy()

    training = [item for item in seen.frames if item[0] is not None]
    plain = [item for item in seen.frames if item[0] is None]
    assert len(training) >= 16  # an update's worth of steps at least
    cameras: set[CameraPerturbation] = set()
    for chosen, track, (x, y, yaw), frames in training:
        assert chosen is not None
        cameras.update(chosen)
        unperturbed = Camera(track).render(x, y, yaw)
        # Every car's frame differs from the plain render of where it stands.
        assert (frames != unperturbed).any(axis=(1, 2)).all()
    # A camera per car per episode: at least one per car, all different.
    assert len(cameras) >= TINY.cars
    # The training's own evaluation (the policy it keeps) drove on the plain render.
    assert plain
    for _, track, (x, y, yaw), frames in plain:
        assert np.array_equal(frames, Camera(track).render(x, y, yaw))


def test_a_model_without_randomisation_trains_on_the_plain_render(seen: Seen) -> None:
    folder = new_model("plain", sensors=["FRONT_FACING_CAMERA"])
    stream: list[events.Event] = []

    def stop() -> bool:
        return any(isinstance(event, events.Update) for event in stream)

    Trainer(folder, stream.append, stop, TINY).run()
    assert seen.frames
    for chosen, track, (x, y, yaw), frames in seen.frames:
        assert chosen is None
        assert np.array_equal(frames, Camera(track).render(x, y, yaw))

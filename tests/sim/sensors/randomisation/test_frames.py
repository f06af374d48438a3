"""What each family of camera randomisation does to the frames a car sees, within bounds,
and that nothing changes when it is off."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sim.env import BatchedDeepRacer, DeepRacerEnv, EnvConfig
from sim.physics.simulation import TrackSimulation
from sim.sensors import camera_scene as scene
from sim.sensors.camera import Camera, Solids
from sim.sensors.observations import Observer
from sim.sensors.randomisation import perturbation as drawn
from sim.sensors.randomisation.frames import SURFACE_OF_LEVEL, SURFACES
from sim.sensors.randomisation.perturbation import (
    PLAIN,
    CameraPerturbation,
    Palette,
    draw_perturbation,
    drivable,
)
from sim.sensors.randomisation.render import PerturbedCamera
from sim.sensors.randomisation.settings import CameraRandomisation
from sim.tracks.track import Track
from tests.sim.sensors.randomisation.helpers import CARS, plain_frames

WALLS = (scene.WALL_LOW_X, scene.WALL_HIGH_X, scene.WALL_LOW_Y, scene.WALL_HIGH_Y)


def seen(sim: TrackSimulation, perturbation: CameraPerturbation, seed: int = 0) -> np.ndarray:
    """Every car's frame through `perturbation`, as the observer gives them, (N, H, W)."""
    observer = Observer(sim, ("camera",))
    observer.perturb_camera(range(sim.n), [perturbation] * sim.n, noise_seed=seed)
    return np.asarray(observer.observe())[..., 0]


# --- off: the plain render, bit for bit --------------------------------------------------


def test_off_a_training_batch_sees_the_plain_render_bit_for_bit(reinvent: Track) -> None:
    config = EnvConfig(track=reinvent, sensors=("camera",))
    assert config.camera_randomisation == CameraRandomisation.OFF
    batch = BatchedDeepRacer(config, CARS, seed=1)
    frames = np.asarray(batch.reset())[..., 0]
    assert np.array_equal(frames, plain_frames(Camera(reinvent), batch.sim))
    assert batch.observer.camera_perturbations is None  # the plain path, nothing made
    batch.step(np.zeros((CARS, 2), dtype=np.float32))
    assert np.array_equal(
        np.asarray(batch.observer.observe())[..., 0], plain_frames(Camera(reinvent), batch.sim)
    )


def test_plain_perturbations_give_the_plain_frames(sim: TrackSimulation, camera: Camera) -> None:
    assert np.array_equal(seen(sim, PLAIN), plain_frames(camera, sim))
    # Objects too: each car's own box, seen through the perturbed camera's plain path.
    fleet = sim.fleet
    ahead = np.stack([fleet.x + 0.8 * np.cos(fleet.yaw), fleet.y + 0.8 * np.sin(fleet.yaw)])
    boxes = Solids(
        x=ahead[0][:, None],
        y=ahead[1][:, None],
        heading=fleet.yaw[:, None],
        length=np.array([0.4]),
        width=np.array([0.3]),
        height=np.array([0.25]),
        side_tone=np.array([scene.BOX_SIDE], dtype=np.uint8),
        top_tone=np.array([scene.BOX_TOP], dtype=np.uint8),
    )
    perturbed = PerturbedCamera(sim.track, camera, sim.n)
    which = np.arange(sim.n)
    got = perturbed.render(which, fleet.x, fleet.y, fleet.yaw, solids=boxes)
    assert np.array_equal(got, camera.render(fleet.x, fleet.y, fleet.yaw, solids=boxes))
    # A car moved to another height sees its box through its own camera, the rest plainly.
    perturbed.set([2], [CameraPerturbation(height_m=0.02)])
    mixed = perturbed.render(which, fleet.x, fleet.y, fleet.yaw, solids=boxes)
    plain = camera.render(fleet.x, fleet.y, fleet.yaw, solids=boxes)
    assert np.array_equal(np.delete(mixed, 2, axis=0), np.delete(plain, 2, axis=0))
    assert not np.array_equal(mixed[2], plain[2])
    assert (mixed[2] == scene.BOX_SIDE).sum() > 50


def test_a_model_without_a_camera_is_never_randomised(reinvent: Track) -> None:
    on = EnvConfig(track=reinvent, sensors=("lidar",), camera_randomisation=CameraRandomisation())
    off = dataclasses.replace(on, camera_randomisation=CameraRandomisation.OFF)
    seen_on, seen_off = BatchedDeepRacer(on, 3, seed=0), BatchedDeepRacer(off, 3, seed=0)
    assert np.array_equal(seen_on.reset(), seen_off.reset())
    assert seen_on.observer.camera_perturbations is None


# --- each family, within its bounds ----------------------------------------------------


def test_light_moves_the_mean_brightness(sim: TrackSimulation, camera: Camera) -> None:
    plain = plain_frames(camera, sim).astype(float)
    darker = seen(sim, CameraPerturbation(gain=0.5)).astype(float)
    assert np.abs(darker - 0.5 * plain).max() <= 0.5 + 1e-9  # 128 + (0.5 v - 128), rounded
    brighter = seen(sim, CameraPerturbation(gain=1.3)).astype(float)
    assert brighter.mean() > 1.2 * plain.mean()
    assert np.abs(brighter - np.clip(1.3 * plain, 0, 255)).max() <= 0.5 + 1e-3
    flatter = seen(sim, CameraPerturbation(contrast=0.7)).astype(float)
    assert flatter.std() == pytest.approx(0.7 * plain.std(), rel=0.02)


def test_noise_raises_pixel_variance_by_its_spread(sim: TrackSimulation, camera: Camera) -> None:
    plain = plain_frames(camera, sim).astype(float)
    observer = Observer(sim, ("camera",))
    observer.perturb_camera(range(sim.n), [CameraPerturbation(noise=8.0)] * sim.n)
    first = np.asarray(observer.observe())[..., 0].astype(float)
    second = np.asarray(observer.observe())[..., 0].astype(float)
    unclipped = (plain > 40) & (plain < 215)  # noise is clipped at black and white
    for frame in (first, second):
        difference = (frame - plain)[unclipped]
        assert difference.std() == pytest.approx(8.0, rel=0.1)
        assert abs(difference.mean()) < 0.5
    assert not np.array_equal(first, second)  # fresh noise in every frame
    assert first.var() > plain.var()


def test_blur_softens_edges_and_keeps_the_brightness(sim: TrackSimulation, camera: Camera) -> None:
    plain = plain_frames(camera, sim).astype(float)
    soft = seen(sim, CameraPerturbation(blur=1.0)).astype(float)

    def edges(frames: np.ndarray) -> float:
        return float(
            np.abs(np.diff(frames, axis=2)).mean() + np.abs(np.diff(frames, axis=1)).mean()
        )

    assert edges(soft) < 0.7 * edges(plain)
    assert soft.mean() == pytest.approx(plain.mean(), abs=1.0)
    assert np.abs(soft - plain).max() <= 255
    slight = seen(sim, CameraPerturbation(blur=0.4)).astype(float)
    assert edges(soft) < edges(slight) < edges(plain)


def _sky_rows(frames: np.ndarray) -> float:
    """Mean count of top rows showing only walls and the background (no ground)."""
    sky = np.isin(frames, [*WALLS, scene.BACKGROUND]).all(axis=2)
    return float(np.mean([np.argmin(rows) if not rows.all() else len(rows) for rows in sky]))


def test_pitch_moves_the_horizon_row(sim: TrackSimulation, camera: Camera) -> None:
    perturbed = PerturbedCamera(sim.track, camera, sim.n)
    down, up = CameraPerturbation(pitch_deg=3.0), CameraPerturbation(pitch_deg=-3.0)
    assert perturbed.camera_for(down).spec.pitch_deg == pytest.approx(camera.spec.pitch_deg + 3)
    assert perturbed.camera_for(down).horizon_row < camera.horizon_row
    assert perturbed.camera_for(up).horizon_row > camera.horizon_row
    plain = _sky_rows(plain_frames(camera, sim))
    looking_down = _sky_rows(seen(sim, down))
    looking_up = _sky_rows(seen(sim, up))
    # 3 degrees at a focal length of 126 pixels: about 6.6 rows.
    assert looking_down < plain - 4 < plain + 4 < looking_up
    assert looking_down > plain - 9 and looking_up < plain + 9


def test_height_moves_the_camera_up_and_down(sim: TrackSimulation, camera: Camera) -> None:
    perturbed = PerturbedCamera(sim.track, camera, sim.n)
    higher = perturbed.camera_for(CameraPerturbation(height_m=0.02))
    assert higher.spec.mount_height == pytest.approx(camera.spec.mount_height + 0.02)
    assert higher.horizon_row == camera.horizon_row  # the pitch is the same

    def field_share(height_m: float) -> float:
        frames = seen(sim, CameraPerturbation(height_m=height_m))
        ground = SURFACE_OF_LEVEL[frames[:, 40:]]
        return float((ground == SURFACES.index("grass")).mean())

    # From higher up every row looks farther ahead and wider: more of the field shows.
    lower, plain, raised = field_share(-0.02), field_share(0.0), field_share(0.02)
    assert lower < plain < raised
    assert plain == pytest.approx(
        float(
            (SURFACE_OF_LEVEL[plain_frames(camera, sim)[:, 40:]] == SURFACES.index("grass")).mean()
        )
    )


def test_colours_recolour_every_surface_through_the_scenes_tones(
    sim: TrackSimulation, camera: Camera
) -> None:
    palette = Palette(road=90, border=170, centre=230, grass=60, background=100, wall_shift=10)
    plain = plain_frames(camera, sim).astype(int)
    recoloured = seen(sim, CameraPerturbation(palette=palette)).astype(int)
    shifts = {
        "walls": 10,
        "road": 90 - scene.ROAD,
        "border": 170 - scene.BORDER,
        "centre": 230 - scene.CENTRE,
        "grass": 60 - scene.GRASS,
        "background": 100 - scene.BACKGROUND,
        "objects": 0,
    }
    expected = plain + np.array([shifts[name] for name in SURFACES])[SURFACE_OF_LEVEL[plain]]
    assert np.array_equal(recoloured, np.clip(expected, 0, 255))
    # Each surface that shows moved as a whole, its grain kept.
    road = SURFACE_OF_LEVEL[plain] == SURFACES.index("road")
    assert road.mean() > 0.2
    assert recoloured[road].std() == pytest.approx(plain[road].std())
    assert set(np.unique(recoloured[plain == scene.CENTRE]).tolist()) == {230}
    for wall in WALLS:
        assert set(np.unique(recoloured[plain == wall]).tolist()) <= {wall + 10}


# --- the draw ------------------------------------------------------------------------------


def test_a_draw_is_reproducible_from_its_seed() -> None:
    settings = CameraRandomisation()
    one = draw_perturbation(settings, np.random.default_rng(7))
    again = draw_perturbation(settings, np.random.default_rng(7))
    other = draw_perturbation(settings, np.random.default_rng(8))
    assert one == again and one != other
    rng = np.random.default_rng(7)
    series = [draw_perturbation(settings, rng) for _ in range(5)]
    rng = np.random.default_rng(7)
    assert series == [draw_perturbation(settings, rng) for _ in range(5)]


@pytest.mark.parametrize("strength", [1.0, 2.0])
def test_draws_stay_within_each_familys_range(strength: float) -> None:
    settings = CameraRandomisation(*(strength,) * 5)
    rng = np.random.default_rng(0)
    draws = [draw_perturbation(settings, rng) for _ in range(500)]
    gains = [d.gain for d in draws]
    assert drawn.LIGHT_GAIN ** (-strength) - 1e-9 <= min(gains) < 0.9
    assert 1.1 < max(gains) <= drawn.LIGHT_GAIN**strength + 1e-9
    assert max(abs(np.log(d.contrast)) for d in draws) <= strength * np.log(drawn.CONTRAST) + 1e-9
    assert 0 <= min(d.noise for d in draws) <= max(d.noise for d in draws)
    assert max(d.noise for d in draws) <= drawn.NOISE_LEVELS * strength
    assert max(d.blur for d in draws) <= drawn.BLUR_PIXELS * strength
    assert max(abs(d.height_m) for d in draws) <= drawn.HEIGHT_M * strength + 1e-9
    assert max(abs(d.pitch_deg) for d in draws) <= drawn.PITCH_DEG * strength + 1e-9
    steps = {round(d.pitch_deg / drawn.PITCH_STEP_DEG, 6) for d in draws}
    assert all(step == int(step) for step in steps) and len(steps) > 5  # shared cameras
    spread = drawn.TONE_LEVELS * strength
    assert all(abs(d.palette.road - scene.ROAD) <= spread + 0.5 for d in draws)
    assert all(abs(d.palette.border - scene.BORDER) <= spread + 0.5 for d in draws)
    assert all(drivable(d.palette) for d in draws)
    assert len({d.palette for d in draws}) > 400


def test_a_family_turned_off_draws_nothing_and_leaves_the_others_alone() -> None:
    everything = draw_perturbation(CameraRandomisation(), np.random.default_rng(3))
    no_pose = draw_perturbation(CameraRandomisation(pose=0.0), np.random.default_rng(3))
    assert (no_pose.height_m, no_pose.pitch_deg) == (0.0, 0.0)
    assert no_pose == dataclasses.replace(everything, height_m=0.0, pitch_deg=0.0)
    nothing = draw_perturbation(CameraRandomisation.OFF, np.random.default_rng(3))
    assert nothing == PLAIN and not nothing.changes_frames


# --- episodes ------------------------------------------------------------------------------


def test_each_car_draws_a_new_camera_every_episode(reinvent: Track) -> None:
    config = EnvConfig(
        track=reinvent, sensors=("camera",), camera_randomisation=CameraRandomisation()
    )
    batch = BatchedDeepRacer(config, 4, seed=11)
    first = np.asarray(batch.reset())[..., 0]
    drawn_cameras = batch.observer.camera_perturbations
    assert drawn_cameras is not None and len(set(drawn_cameras)) == 4
    assert all(p.changes_frames for p in drawn_cameras)
    assert not np.array_equal(first, plain_frames(Camera(reinvent), batch.sim))
    # Car 0 steers hard left at speed and leaves the track; the others drive on straight.
    actions = np.array([[1.0, 1.0], [0.0, -0.5], [0.0, -0.5], [0.0, -0.5]], dtype=np.float32)
    for _ in range(60):
        _, _, terminated, truncated, _ = batch.step(actions)
        if terminated[0] or truncated[0]:
            break
    assert terminated[0]
    now = batch.observer.camera_perturbations
    assert now is not None and now[0] != drawn_cameras[0]
    assert now[1:] == drawn_cameras[1:]
    # The same seed draws the same cameras.
    twin = BatchedDeepRacer(config, 4, seed=11)
    twin.reset()
    assert twin.observer.camera_perturbations == drawn_cameras


def test_the_single_car_env_draws_from_its_seed(reinvent: Track) -> None:
    config = EnvConfig(
        track=reinvent, sensors=("camera",), camera_randomisation=CameraRandomisation()
    )
    env = DeepRacerEnv(config)
    first, _ = env.reset(seed=5)
    again, _ = DeepRacerEnv(config).reset(seed=5)
    assert np.array_equal(first, again)
    cameras = env.observer.camera_perturbations
    env.reset()
    assert env.observer.camera_perturbations != cameras
    plain_env = DeepRacerEnv(
        dataclasses.replace(config, camera_randomisation=CameraRandomisation.OFF)
    )
    plain, _ = plain_env.reset(seed=5)
    assert not np.array_equal(first, plain)
    assert plain_env.observer.camera_perturbations is None

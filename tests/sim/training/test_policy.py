"""Policy files: tensors only, rebuilt from metadata, every name and shape checked."""

from __future__ import annotations

import pickle
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from safetensors.torch import save

from sim.deepracer.action_space import FULL_RANGE_CONTINUOUS, ActionSpace, discrete_grid
from sim.deepracer.files import NEURAL_NETWORKS, ModelMetadata
from sim.garage.folder import ModelFolder
from sim.physics.simulation import TrackSimulation
from sim.sensors.observations import SensorOptions
from sim.tracks.catalog import resolve_track
from sim.training.numpy_policy import NumpyActor
from sim.training.policy import (
    PolicyError,
    build_network,
    load_policy,
    observation_tensors,
    policy_bytes,
    save_policy,
)
from sim.training.policy_driver import PolicyDriver, _batched, driver_for_model
from sim.training.runtimes import (
    NUMPY_CAMERA,
    TORCH_CAMERA,
    policy_runtime,
    policy_runtimes,
    runtime_version,
)

DISCRETE = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("vector",))
CONTINUOUS_LIDAR = ModelMetadata(FULL_RANGE_CONTINUOUS, ("lidar",))
SMALL_CAMERA = SensorOptions(camera_width=64, camera_height=48)


def _same_weights(a: torch.nn.Module, b: torch.nn.Module) -> bool:
    sa, sb = a.state_dict(), b.state_dict()
    return sa.keys() == sb.keys() and all(torch.equal(sa[k], sb[k]) for k in sa)


@pytest.mark.parametrize("metadata", [DISCRETE, CONTINUOUS_LIDAR], ids=["discrete", "lidar"])
def test_a_saved_policy_loads_back_with_the_same_weights(
    tmp_path: Path, metadata: ModelMetadata
) -> None:
    network = build_network(metadata)
    save_policy(tmp_path / "policy.safetensors", network)
    loaded = load_policy(tmp_path / "policy.safetensors", metadata)
    assert _same_weights(network, loaded)
    assert _same_weights(network, load_policy(policy_bytes(network), metadata))


def test_camera_and_lidar_together_use_a_small_cnn() -> None:
    metadata = ModelMetadata(FULL_RANGE_CONTINUOUS, ("camera", "lidar"))
    network = build_network(metadata, SMALL_CAMERA)
    assert network.camera is not None
    frames = torch.zeros((3, 48, 64, 1), dtype=torch.uint8)
    params, values = network({"camera": frames, "lidar": torch.ones((3, 64))})
    assert params.shape == (3, 2) and values.shape == (3, 1)
    loaded = load_policy(policy_bytes(network), metadata, SMALL_CAMERA)
    assert _same_weights(network, loaded)


def test_a_pickle_is_rejected_without_being_unpickled(tmp_path: Path) -> None:
    class Boom:
        def __reduce__(self) -> tuple[object, ...]:
            return (print, ("pickle payload ran!",))

    path = tmp_path / "policy.safetensors"
    path.write_bytes(pickle.dumps({"weights": Boom()}))
    with pytest.raises(PolicyError, match="not a safetensors policy"):
        load_policy(path, DISCRETE)


def test_a_torch_save_file_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "policy.safetensors"
    torch.save(build_network(DISCRETE).state_dict(), path)
    with pytest.raises(PolicyError):
        load_policy(path, DISCRETE)


def test_a_policy_for_another_action_space_is_rejected() -> None:
    data = policy_bytes(build_network(DISCRETE))
    other = ModelMetadata(discrete_grid(30.0, 7, 3.0, 2), ("vector",))
    with pytest.raises(PolicyError, match="different car"):
        load_policy(data, other)


def _forged(metadata: ModelMetadata, change: str) -> bytes:
    """Safetensors data with the right architecture facts but doctored tensors."""
    network = build_network(metadata)
    tensors = {k: v.clone().contiguous() for k, v in network.state_dict().items()}
    if change == "shape":
        tensors["action_head.weight"] = torch.zeros((3, 3))
    elif change == "extra":
        tensors["payload"] = torch.zeros(1)
    elif change == "missing":
        del tensors["value_head.bias"]
    elif change == "dtype":
        tensors["value_head.bias"] = tensors["value_head.bias"].double()
    elif change == "nan":
        tensors["value_head.bias"] = torch.full_like(tensors["value_head.bias"], float("nan"))
    return bytes(save(tensors, metadata=network.spec.facts()))


@pytest.mark.parametrize("change", ["shape", "extra", "missing", "dtype", "nan"])
def test_doctored_tensors_are_rejected(change: str) -> None:
    with pytest.raises(PolicyError):
        load_policy(_forged(DISCRETE, change), DISCRETE)


def test_truncated_or_garbage_data_is_rejected() -> None:
    data = policy_bytes(build_network(DISCRETE))
    for bad in (b"", b"\x00" * 4, data[: len(data) // 2], struct.pack("<Q", 10**12) + b"{}"):
        with pytest.raises(PolicyError):
            load_policy(bad, DISCRETE)


def test_safetensors_without_racer_tui_facts_are_rejected() -> None:
    tensors = {k: v.contiguous() for k, v in build_network(DISCRETE).state_dict().items()}
    with pytest.raises(PolicyError, match="not written by racer-tui"):
        load_policy(bytes(save(tensors)), DISCRETE)


def test_the_driver_gives_one_deterministic_action_per_car() -> None:
    track = resolve_track("hairpin-circuit")
    driver = PolicyDriver(build_network(DISCRETE), DISCRETE, name="m", content_hash="h")
    sim = TrackSimulation(track, 3)
    sim.reset_all()
    driver.reset(sim)
    first, second = driver.act(sim), driver.act(sim)
    assert first.steering_deg.shape == first.speed.shape == first.action_index.shape == (3,)
    assert np.array_equal(first.action_index, second.action_index)
    table = DISCRETE.action_space.to_metadata()
    assert isinstance(table, list)
    for i, index in enumerate(first.action_index.tolist()):
        assert first.speed[i] == table[index]["speed"]


def test_a_continuous_driver_reports_no_action_index() -> None:
    track = resolve_track("hairpin-circuit")
    driver = PolicyDriver(
        build_network(CONTINUOUS_LIDAR), CONTINUOUS_LIDAR, name="m", content_hash="h"
    )
    sim = TrackSimulation(track, 2)
    sim.reset_all()
    action = driver.act(sim)  # reset happens on first use of a new simulation
    assert action.action_index.tolist() == [-1, -1]
    assert np.all((action.speed >= 0.1) & (action.speed <= 4.0))


def test_a_model_without_a_policy_says_to_train_it(model: ModelFolder) -> None:
    with pytest.raises(PolicyError, match="racer-tui train tiny"):
        driver_for_model(model)


def test_driver_for_model_names_the_car_by_its_content_hash(model: ModelFolder) -> None:
    save_policy(model.policy_file, build_network(model.metadata()))
    driver = driver_for_model(model)
    assert driver.name == "tiny"
    assert driver.content_hash == model.content_hash()


def test_a_bundle_drives_with_the_weights_it_carries(model: ModelFolder, tmp_path: Path) -> None:
    from sim.garage.bundle import export_bundle, read_bundle
    from sim.training.policy_driver import driver_for_bundle

    network = build_network(model.metadata())
    save_policy(model.policy_file, network)
    bundle = read_bundle(export_bundle(model, tmp_path / "tiny"))
    driver = driver_for_bundle(bundle)
    assert (driver.name, driver.content_hash) == ("tiny", model.content_hash())
    assert _same_weights(driver.network, network)


@pytest.mark.parametrize(
    "metadata",
    [DISCRETE, CONTINUOUS_LIDAR, ModelMetadata(FULL_RANGE_CONTINUOUS, ("lidar", "vector"))],
    ids=["discrete", "lidar", "lidar+vector"],
)
def test_the_numpy_actor_drives_exactly_like_the_network(metadata: ModelMetadata) -> None:
    network = build_network(metadata)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.normal_(0.0, 0.5)  # spread the outputs so argmax ties are unlikely
    rng = np.random.default_rng(0)
    shapes = dict(zip(network.spec.sensors, network.spec.input_shapes, strict=True))
    obs_dict = {
        name: rng.uniform(0.0, 2.0, (16, *shape)).astype(np.float32)
        for name, shape in shapes.items()
    }
    obs = obs_dict if len(obs_dict) > 1 else next(iter(obs_dict.values()))
    expected = network.act(observation_tensors(obs)).detach().numpy()
    got = NumpyActor(network).act(obs)
    if metadata.action_space.kind == "discrete":
        assert np.array_equal(got, expected)
    else:
        assert np.allclose(got, expected, atol=1e-5)


@pytest.mark.parametrize("network_size", NEURAL_NETWORKS)
@pytest.mark.parametrize(
    ("sensors", "action_space"),
    [
        (("camera",), discrete_grid(30.0, 5, 3.0, 2)),
        (("camera", "lidar"), FULL_RANGE_CONTINUOUS),
    ],
    ids=["camera", "camera+lidar"],
)
@pytest.mark.parametrize("cars", [1, 3])
def test_the_numpy_actor_computes_a_camera_network_as_torch_does(
    network_size: str, sensors: tuple[str, ...], action_space: ActionSpace, cars: int
) -> None:
    """The same function in another order of sums (runtime version 2): outputs within
    float32 rounding of torch's, for every network size, alone and in a batch, with the
    Observer's one-channel frames (channel axis added last) and a copy laid out plainly."""
    metadata = ModelMetadata(action_space, sensors, neural_network=network_size)
    options = SensorOptions(camera_width=128, camera_height=90)  # odd sizes: pools crop
    network = build_network(metadata, options)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.normal_(0.0, 0.1)
    rng = np.random.default_rng(cars)
    frames = rng.integers(0, 256, (cars, 90, 128), dtype=np.uint8)[..., None]
    for camera in (frames, np.ascontiguousarray(frames)):
        obs: Any = camera
        if "lidar" in sensors:
            obs = {"camera": camera, "lidar": rng.uniform(0.1, 2.0, (cars, 64)).astype(np.float32)}
        with torch.inference_mode():
            expected = network.action_parameters(network.features(observation_tensors(obs)))
        got = NumpyActor(network).action_parameters(obs)
        scale = float(expected.abs().max())
        assert np.allclose(got, expected.numpy(), rtol=0.0, atol=1e-5 * scale)


@pytest.mark.parametrize("version", [TORCH_CAMERA, NUMPY_CAMERA])
def test_several_cars_act_in_one_batch_laid_out_as_one_cars_frames(version: int) -> None:
    """A head-to-head model drives its cars in one forward pass: the batch keeps a single
    car's frame layout (the channel axis added last), so torch takes the same plain path
    for it (runtime version 1), and each car gets the action it would get alone, under
    each runtime version."""
    track = resolve_track("reinvent_base")
    metadata = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("camera",))
    driver = PolicyDriver(
        build_network(metadata),
        metadata,
        name="cam",
        content_hash="cam",
        runtime_version=version,
    )
    sims = [TrackSimulation(track, 1, seed=k) for k in range(3)]
    for k, sim in enumerate(sims):
        sim.reset_car(0, 2.0 * k)
        driver.reset(sim)
    one = [driver._observe(sim) for sim in sims]
    assert one[0].strides[-1] == 0  # one car's frames: the channel axis added last
    batch = _batched(one)
    assert batch.strides[-1] == 0 and np.array_equal(batch, np.concatenate(one))
    together = driver.act_many(sims)
    alone = [driver.act(sim) for sim in sims]
    for many, single in zip(together, alone, strict=True):
        assert np.array_equal(many.action_index, single.action_index)
        assert np.array_equal(many.steering_deg, single.steering_deg)


def test_the_policy_runtimes_are_stable_and_leave_torchs_generator_alone() -> None:
    policy_runtimes.cache_clear()
    torch.manual_seed(3)
    expected = torch.rand(4)
    torch.manual_seed(3)
    names = policy_runtimes()
    assert torch.equal(torch.rand(4), expected)  # a seeded training draws the same
    assert sorted(names) == [TORCH_CAMERA, NUMPY_CAMERA]
    # Version 1 is named as runtimes were before they had versions, so the races recorded
    # then are still found here; version 2 says its number and its library.
    assert names[TORCH_CAMERA].startswith(f"torch {torch.__version__.split('+')[0]} ")
    assert names[NUMPY_CAMERA].startswith(f"v2 numpy {np.__version__} ")
    assert policy_runtime() == names[NUMPY_CAMERA]  # races take the current version
    policy_runtimes.cache_clear()
    assert policy_runtimes() == names  # the same numerics, the same names
    assert runtime_version(names[TORCH_CAMERA]) == TORCH_CAMERA
    assert runtime_version("torch 2.13.0 arm64 0123456789ab") is None


def test_a_camera_policy_drives_under_each_runtime_version_it_is_asked_for() -> None:
    track = resolve_track("reinvent_base")
    metadata = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("camera",))
    network = build_network(metadata)
    driver = PolicyDriver(network, metadata, name="cam", content_hash="cam")
    assert driver.runtime == policy_runtimes()[NUMPY_CAMERA]
    assert driver.under(driver.runtime) is driver
    assert driver.under("torch 2.13.0 arm64 0123456789ab") is None  # not this machine's
    then = driver.under(policy_runtimes()[TORCH_CAMERA])
    assert then is not None and then.runtime == policy_runtimes()[TORCH_CAMERA]
    assert (then.name, then.content_hash) == (driver.name, driver.content_hash)
    sim = TrackSimulation(track, 1, seed=2)
    sim.reset_car(0, 3.0)
    frames = then._observe(sim)
    with torch.inference_mode():
        in_torch = network.act(observation_tensors(frames)).numpy()
    # Version 1 drives a camera network in torch, as races recorded then were driven.
    assert np.array_equal(then.actions(sim), in_torch)
    # Version 2's weights are the network's when the driver was made (the trainer makes
    # one per evaluation), though the network trains on.
    actor = NumpyActor(network)
    before = actor.action_parameters(frames)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.add_(0.5)
    assert np.array_equal(actor.action_parameters(frames), before)
    assert not np.array_equal(NumpyActor(network).action_parameters(frames), before)

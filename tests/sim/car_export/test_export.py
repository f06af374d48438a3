"""Exporting for the car: the archive a physical DeepRacer loads.

The graph is checked the way the car checks it: OpenVINO (the car's runtime, the test
suite's converter) and TensorFlow (which wrote DeepRacer's own graphs) read the frozen
graph by the car's tensor names and give the policy's outputs for frames of racer-tui's
own camera; the archive passes the car loader's
rules as aws-deepracer-systems-pkg applies them; and racer-tui's own reader and runner
(what `model import` uses) give the same answers.
"""

from __future__ import annotations

import json
import os
import tarfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from sim.car_archive.archive import read_car_archive
from sim.car_archive.car_mapping import CarMapping, car_actions
from sim.car_archive.graph_def import SUPPORTED_OPS, read_graph
from sim.car_archive.policy import CarPolicy
from sim.car_export.export import GRAPH_OPS, car_refusal, export_car_archive
from sim.garage.folder import ModelError, ModelFolder
from sim.garage.options import new_model
from sim.sensors.batched import Camera, CameraSpec
from sim.tracks.catalog import resolve_track
from sim.training import events
from sim.training.policy import build_network, load_policy, observation_tensors, save_policy
from sim.training.trainer import RunOptions, Trainer
from tests.sim.car_export.graphs import one_sentence

ov = pytest.importorskip("openvino", reason="the car extra (OpenVINO) is not installed")

# Importing TensorFlow takes a worker about 15 s: its tests share one (`--dist loadgroup`).
IN_TENSORFLOW_S_WORKER = pytest.mark.xdist_group("tensorflow")

CAMERA = "main_level/agent/main/online/network_0/FRONT_FACING_CAMERA/FRONT_FACING_CAMERA"
LIDAR = "main_level/agent/main/online/network_0/LIDAR/LIDAR"
POLICY = "main_level/agent/main/online/network_1/ppo_head_0/policy"
TINY = RunOptions(minutes=5, cars=2, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)
# Attributes TensorFlow 1 writes for each op (what DeepRacer's own frozen graphs carry);
# newer attributes (explicit_paddings, for example) would trip OpenVINO 2021 and TF 2.4.
TF1_ATTRIBUTES = {
    "AvgPool": {"T", "ksize", "strides", "padding", "data_format"},
    "BiasAdd": {"T", "data_format"},
    "ConcatV2": {"N", "T", "Tidx"},
    "Const": {"dtype", "value"},
    "Conv2D": {"T", "strides", "padding", "data_format", "dilations", "use_cudnn_on_gpu"},
    "MatMul": {"T", "transpose_a", "transpose_b"},
    "Maximum": {"T"},
    "Minimum": {"T"},
    "Placeholder": {"dtype", "shape"},
    "RealDiv": {"T"},
    "Relu": {"T"},
    "Reshape": {"T", "Tshape"},
    "Softmax": {"T"},
    "Tanh": {"T"},
}


def train_briefly(folder: ModelFolder) -> ModelFolder:
    """One PPO update of real training: the weights have moved from their initialisation."""
    stream: list[events.Event] = []

    def enough() -> bool:
        return any(isinstance(event, events.Update) for event in stream)

    Trainer(folder, stream.append, enough, TINY).run()
    assert folder.has_policy()
    return folder


@pytest.fixture(scope="module")
def home(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    with pytest.MonkeyPatch.context() as patch:
        path = tmp_path_factory.mktemp("home")
        patch.setenv("RACER_TUI_HOME", str(path))
        yield path


@pytest.fixture(scope="module")
def models(home: Path) -> dict[str, ModelFolder]:
    """Freshly trained models: camera discrete, camera continuous, camera and lidar."""
    return {
        "discrete": train_briefly(new_model("cam-discrete", sensors=["camera"])),
        "continuous": train_briefly(
            new_model("cam-continuous", sensors=["camera"], continuous=True)
        ),
        "lidar": train_briefly(new_model("cam-lidar", sensors=["camera", "lidar"])),
    }


def simulator_frames(count: int = 20) -> np.ndarray:
    """What racer-tui's camera sees at `count` places round reinvent_base, (N, 120, 160)."""
    track = resolve_track("reinvent_base")
    index = np.linspace(0, len(track.center) - 1, count, endpoint=False).astype(int)
    nxt = (index + 1) % len(track.center)
    x, y = track.center[index, 0], track.center[index, 1]
    yaw = np.arctan2(track.center[nxt, 1] - y, track.center[nxt, 0] - x)
    frames = Camera(track, CameraSpec()).render(x, y, yaw)
    assert frames.shape == (count, 120, 160) and frames.dtype == np.uint8
    return frames


def lidar_readings(count: int = 20) -> np.ndarray:
    return np.random.default_rng(7).uniform(0.1, 2.0, (count, 64)).astype(np.float32)


def policy_outputs(folder: ModelFolder, frames: np.ndarray, lidar: np.ndarray) -> np.ndarray:
    """What racer-tui's policy gives: softmax of the logits, or the clipped mean."""
    metadata = folder.metadata()
    network = load_policy(folder.policy_file, metadata)
    obs: Any = frames[..., np.newaxis]
    if "lidar" in metadata.sensors:
        obs = {"camera": obs, "lidar": lidar}
    with torch.inference_mode():
        params = network.action_parameters(network.features(observation_tensors(obs)))
    if metadata.action_space.kind == "discrete":
        return torch.softmax(params, dim=1).numpy()
    return params.clamp(-1.0, 1.0).numpy()


def openvino_outputs(archive: Path, feeds: dict[str, np.ndarray]) -> np.ndarray:
    """The archive's graph through OpenVINO at float32, fed by the car's input names."""
    with tarfile.open(archive) as tar:
        member = tar.extractfile("agent/model.pb")
        assert member is not None
        graph = member.read()
    core = ov.Core()
    path = archive.with_suffix(".pb")
    path.write_bytes(graph)
    model = core.read_model(str(path))
    outputs = [port.get_any_name() for port in model.outputs]
    assert outputs == ["main_level/agent/main/online/network_1/ppo_head_0/policy:0"]
    compiled = core.compile_model(model, "CPU", {"INFERENCE_PRECISION_HINT": "f32"})
    named = {port.get_any_name().removesuffix(":0"): i for i, port in enumerate(compiled.inputs)}
    assert set(named) == set(feeds)
    result = compiled({named[name]: value for name, value in feeds.items()})
    return np.asarray(next(iter(result.values())))


@pytest.mark.parametrize("kind", ["discrete", "continuous", "lidar"])
def test_openvino_runs_the_exported_graph_as_the_policy_drives(
    models: dict[str, ModelFolder], tmp_path: Path, kind: str
) -> None:
    folder = models[kind]
    written = export_car_archive(folder, tmp_path / folder.name)
    assert written.path == tmp_path / f"{folder.name}.tar.gz"
    frames, lidar = simulator_frames(), lidar_readings()
    feeds = {CAMERA: frames[..., np.newaxis].astype(np.float32)}  # raw 0..255, as the car
    if kind == "lidar":
        feeds[LIDAR] = lidar
    expected = policy_outputs(folder, frames, lidar)
    got = openvino_outputs(written.path, feeds)
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, atol=1e-4, rtol=0)
    # A briefly trained policy's outputs differ little from frame to frame: the export must
    # reproduce those differences too, not only the values.
    spread = np.ptp(expected, axis=0).max()
    assert np.abs(got - expected).max() < 0.01 * spread
    if kind != "continuous":
        assert (got.argmax(axis=1) == expected.argmax(axis=1)).all()
        np.testing.assert_allclose(got.sum(axis=1), 1.0, atol=1e-5)


@IN_TENSORFLOW_S_WORKER
def test_a_decisive_policy_chooses_the_same_actions_through_openvino(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    """The trained camera network with every weight shaken (seeded): the chosen action
    changes from frame to frame, so a wrong pixel or feature order would show."""
    source = models["discrete"]
    folder = new_model("cam-decisive", sensors=["camera"])
    network = load_policy(source.policy_file, source.metadata())
    generator = torch.Generator().manual_seed(3)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.add_(torch.randn(parameter.shape, generator=generator) * 0.1)
    save_policy(folder.policy_file, network)
    frames = simulator_frames()
    expected = policy_outputs(folder, frames, lidar_readings())
    assert len(set(expected.argmax(axis=1).tolist())) >= 3
    path = export_car_archive(folder, tmp_path / "decisive").path
    feeds = {CAMERA: frames[..., np.newaxis].astype(np.float32)}
    for got in (openvino_outputs(path, feeds), tensorflow_outputs(path, feeds)):
        np.testing.assert_allclose(got, expected, atol=1e-4, rtol=0)
        assert (got.argmax(axis=1) == expected.argmax(axis=1)).all()


def tensorflow_outputs(archive: Path, feeds: dict[str, np.ndarray]) -> np.ndarray:
    """The archive's graph imported by TensorFlow (as a TensorFlow 1 frozen graph, the way
    DeepRacer's tools load model.pb) and run by the car's tensor names."""
    os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "2")
    tf = pytest.importorskip("tensorflow", reason="the car extra (TensorFlow) is not installed")
    with tarfile.open(archive) as tar:
        member = tar.extractfile("agent/model.pb")
        assert member is not None
        graph_def = tf.compat.v1.GraphDef.FromString(member.read())
    with tf.Graph().as_default() as graph:
        tf.compat.v1.import_graph_def(graph_def, name="")
        with tf.compat.v1.Session(graph=graph) as session:
            output = graph.get_tensor_by_name(f"{POLICY}:0")
            inputs = {graph.get_tensor_by_name(f"{name}:0"): value for name, value in feeds.items()}
            return np.asarray(session.run(output, feed_dict=inputs))


@IN_TENSORFLOW_S_WORKER
@pytest.mark.parametrize("kind", ["discrete", "continuous", "lidar"])
def test_tensorflow_runs_the_exported_graph_as_the_policy_drives(
    models: dict[str, ModelFolder], tmp_path: Path, kind: str
) -> None:
    folder = models[kind]
    path = export_car_archive(folder, tmp_path / folder.name).path
    frames, lidar = simulator_frames(), lidar_readings()
    feeds = {CAMERA: frames[..., np.newaxis].astype(np.float32)}
    if kind == "lidar":
        feeds[LIDAR] = lidar
    expected = policy_outputs(folder, frames, lidar)
    got = tensorflow_outputs(path, feeds)
    np.testing.assert_allclose(got, expected, atol=1e-4, rtol=0)
    assert np.abs(got - expected).max() < 0.01 * np.ptp(expected, axis=0).max()
    if kind != "continuous":
        assert (got.argmax(axis=1) == expected.argmax(axis=1)).all()


def test_racer_tui_runs_its_own_export_as_the_policy_drives(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    for kind in ("discrete", "continuous"):
        folder = models[kind]
        archive = read_car_archive(export_car_archive(folder, tmp_path / kind).path)
        assert archive.metadata == folder.metadata()
        frames = simulator_frames()
        policy = CarPolicy(archive)
        expected = policy_outputs(folder, frames, lidar_readings())
        np.testing.assert_allclose(policy.outputs(frames), expected, atol=1e-5, rtol=0)


def test_the_archive_passes_the_car_loaders_rules(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    path = export_car_archive(models["discrete"], tmp_path / "car").path
    with tarfile.open(path, "r:gz") as tar:
        members = tar.getmembers()
        names = [member.name for member in members]
        assert sorted(names) == ["agent/model.pb", "model_metadata.json"]
        assert all(member.isreg() for member in members)
        metadata = json.loads(tar.extractfile("model_metadata.json").read())  # type: ignore[union-attr]
    # model_loader_node.py: `ext not in (".pb")` tests a substring of ".pb", so a file with
    # no extension counts as a model too; the car wants exactly one.
    model_files = [name for name in names if os.path.splitext(name)[1] in ".pb"]
    assert model_files == ["agent/model.pb"]
    # deepracer_navigation_node.py's validate_action_space, discrete: every action has
    # steering_angle and speed.
    assert metadata["action_space_type"] == "discrete"
    assert all({"steering_angle", "speed"} <= set(a) for a in metadata["action_space"])
    assert metadata["sensor"] == ["FRONT_FACING_CAMERA"]
    assert metadata["training_algorithm"] == "clipped_ppo"


def test_a_continuous_archive_has_valid_ranges(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    path = export_car_archive(models["continuous"], tmp_path / "car").path
    with tarfile.open(path, "r:gz") as tar:
        metadata = json.loads(tar.extractfile("model_metadata.json").read())  # type: ignore[union-attr]
    space = metadata["action_space"]
    assert metadata["action_space_type"] == "continuous"
    for key in ("steering_angle", "speed"):
        assert space[key]["high"] > space[key]["low"]


def test_the_graph_uses_only_tensorflow_1_ops_and_attributes(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    seen: set[str] = set()
    for kind in ("discrete", "continuous", "lidar"):
        path = export_car_archive(models[kind], tmp_path / kind).path
        with tarfile.open(path, "r:gz") as tar:
            graph = read_graph(tar.extractfile("agent/model.pb").read(), kind)  # type: ignore[union-attr]
        for node in graph.nodes.values():
            assert node.op in GRAPH_OPS
            assert set(node.attrs) == TF1_ATTRIBUTES[node.op], node.name
            seen.add(node.op)
    assert seen == GRAPH_OPS
    assert GRAPH_OPS <= SUPPORTED_OPS


def test_one_model_always_exports_the_same_bytes(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    first = export_car_archive(models["discrete"], tmp_path / "a").path.read_bytes()
    second = export_car_archive(models["discrete"], tmp_path / "b").path.read_bytes()
    assert first == second


def test_an_existing_file_is_replaced_only_on_purpose(
    models: dict[str, ModelFolder], tmp_path: Path
) -> None:
    target = tmp_path / "kept.tar.gz"
    target.write_bytes(b"someone's model")
    with pytest.raises(ModelError) as raised:
        export_car_archive(models["discrete"], target)
    assert "--force" in str(raised.value)
    assert target.read_bytes() == b"someone's model"
    export_car_archive(models["discrete"], target, replace=True)
    assert read_car_archive(target).metadata == models["discrete"].metadata()


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"sensors": ["vector"]}, "VECTOR is racer-tui's own"),
        ({"sensors": ["lidar"]}, "has no camera"),
    ],
)
def test_what_the_car_cannot_run_is_refused_in_one_sentence(
    tmp_path: Path, options: dict[str, Any], words: str
) -> None:
    folder = new_model("refused", **options)
    assert car_refusal(folder.metadata()) is not None
    save_policy(folder.policy_file, build_network(folder.metadata()))
    with pytest.raises(ModelError) as raised:
        export_car_archive(folder, tmp_path / "out")
    message = str(raised.value)
    assert words in message and one_sentence(message)
    assert not (tmp_path / "out.tar.gz").exists()


def test_a_sac_model_is_refused_for_the_car(models: dict[str, ModelFolder]) -> None:
    metadata = replace(models["continuous"].metadata(), training_algorithm="sac")
    assert "PPO models" in (car_refusal(metadata) or "")


def test_the_car_drives_half_the_top_speed_at_80_percent_throttle(
    models: dict[str, ModelFolder],
) -> None:
    space = models["discrete"].metadata().action_space
    mapping = CarMapping.of(space)
    top = max(action.speed for action in space.actions)
    assert mapping.throttle(top) == pytest.approx(1.0)
    assert mapping.throttle(top / 2) == pytest.approx(0.8)
    assert mapping.throttle(0.0) == 0.0
    widest = max(abs(action.steering_angle) for action in space.actions)
    table = car_actions(space)
    assert len(table) == len(space.actions)
    for row, action in zip(table, space.actions, strict=True):
        assert row.steering == pytest.approx(action.steering_angle / widest)
        assert 0.0 < row.throttle <= 1.0

"""Exporting a racer-tui model for a physical DeepRacer: the car archive it loads.

The archive is a `.tar.gz` holding `model_metadata.json` at its root and one frozen
TensorFlow graph, `agent/model.pb`, and nothing else: the car's model loader
(aws-deepracer-systems-pkg) searches the archive for model files, counting files without
an extension too, and refuses it unless it finds exactly one.

The graph is the policy network's deterministic actor written as TensorFlow 1 ops that
OpenVINO 2021's TensorFlow front end and TensorFlow 2.4 both know (`GRAPH_OPS`), with the
attributes TensorFlow 1 writes and nothing newer, under the names the car feeds and reads
(as DeepRacer's simulator names them, rl_coach's `main_level/agent/main/online/...`):

- each sensor is a Placeholder `network_0/<SENSOR>/<SENSOR>`: the camera `[?, 120, 160, 1]`
  raw 0..255 as the car feeds it (the graph divides by 255 itself), lidar `[?, 64]` metres;
- the camera's encoder is written in TensorFlow's NHWC layout; torch flattens NCHW, so the
  first dense layer's rows are reordered to NHWC instead of transposing the image;
- `network_1/ppo_head_0/policy` is the softmax over a discrete space's actions (the car
  takes the argmax) or, for a continuous space, the Gaussian mean clipped to -1..1 (the car
  scales it linearly to the space's ranges), exactly what `PolicyNetwork.act` takes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from torch import nn

from sim.car_archive.archive import (
    AGENT_SCOPES,
    INPUT_NODE,
    OUTPUT_NODES,
    car_archive_bytes,
    read_car_archive,
)
from sim.car_archive.car_mapping import CarAction, car_actions, car_export_notes, car_refusal
from sim.car_archive.errors import CarModelError
from sim.car_archive.file_names import car_archive_path
from sim.car_export.graph_writer import GraphWriter, attr_b, attr_i, attr_ints, attr_s, attr_type
from sim.deepracer.files import SENSOR_FILE_NAMES, ModelMetadata
from sim.garage.folder import ModelError, ModelFolder, write_export
from sim.training.policy import CAMERA_POOL, PolicyNetwork, load_policy

# Every op the exported graph uses; a test holds the written graphs to this list.
GRAPH_OPS = frozenset(
    {
        "AvgPool",
        "BiasAdd",
        "ConcatV2",
        "Const",
        "Conv2D",
        "MatMul",
        "Maximum",
        "Minimum",
        "Placeholder",
        "RealDiv",
        "Relu",
        "Reshape",
        "Softmax",
        "Tanh",
    }
)
_AGENT = AGENT_SCOPES["clipped_ppo"]  # SAC is not exported (see car_refusal)
_ONLINE = f"main_level/agent/{_AGENT}/online"


@dataclass(frozen=True)
class CarExport:
    """A written car archive and what the car will do with each action."""

    path: Path
    metadata: ModelMetadata
    actions: tuple[CarAction, ...]
    notes: tuple[str, ...] = ()


def export_car_archive(folder: ModelFolder, out: Path, *, replace: bool = False) -> CarExport:
    """Write `folder`'s trained policy as a car archive at `out`, atomically."""
    target = car_archive_path(out)
    if target.exists() and not replace:
        raise ModelError(
            f"{target} already exists; choose another file name, or replace it on purpose "
            "(`racer-tui model export --format car --force`)."
        )
    metadata = folder.metadata()
    if folder.drives_with_car_archive():  # hand DeepRacer's own graph on as it is
        data = folder.car_archive_file.read_bytes()
        try:
            read_car_archive(folder.car_archive_file)
        except CarModelError as error:
            raise ModelError(f"model {folder.name!r}: {error}") from None
        write_export(target, data)
        return CarExport(
            target, metadata, car_actions(metadata.action_space), car_export_notes(metadata)
        )
    refusal = car_refusal(metadata)
    if refusal is not None:
        raise ModelError(f"model {folder.name!r} cannot be exported for the car: {refusal}.")
    if not folder.has_policy():
        raise ModelError(
            f"model {folder.name!r} has no trained policy to export; train it first with "
            f"`racer-tui train {folder.name}`."
        )
    network = load_policy(folder.policy_file, metadata)
    graph = policy_graph(network)
    metadata_bytes = (json.dumps(metadata.to_json(), indent=4) + "\n").encode("utf-8")
    write_export(target, car_archive_bytes(metadata_bytes, graph))
    return CarExport(
        target, metadata, car_actions(metadata.action_space), car_export_notes(metadata)
    )


def policy_graph(network: PolicyNetwork) -> bytes:
    """The deterministic actor of `network` as a frozen GraphDef (see the module doc)."""
    spec = network.spec
    g = GraphWriter()
    encoded: list[str] = []
    for sensor, shape in zip(spec.sensors, spec.input_shapes, strict=True):
        name = SENSOR_FILE_NAMES[sensor]
        x = g.placeholder(INPUT_NODE.format(agent=_AGENT, sensor=name), [-1, *shape])
        scope = f"{_ONLINE}/network_1/{name}"
        if sensor == "camera":
            assert network.camera is not None
            encoded.append(_camera(g, scope, x, network.camera, shape))
        elif sensor == "lidar":
            range_ = g.const(f"{scope}/range", np.float32(spec.lidar_range))
            encoded.append(g.op(f"{scope}/scaled", "RealDiv", x, range_))
        else:
            encoded.append(x)
    features = encoded[0]
    if len(encoded) > 1:
        axis = g.const(f"{_ONLINE}/network_1/concat/axis", np.int32(1))
        features = g.op(
            f"{_ONLINE}/network_1/concat",
            "ConcatV2",
            *encoded,
            axis,
            N=attr_i(len(encoded)),
            Tidx=attr_type(np.int32),
        )
    x = features
    dense = [layer for layer in network.policy_mlp if isinstance(layer, nn.Linear)]
    for index, layer in enumerate(dense):
        scope = f"{_ONLINE}/network_1/middleware_fc_embedder/Dense_{index}"
        x = g.op(f"{scope}/Tanh", "Tanh", _dense(g, scope, x, layer))
    head = f"{_ONLINE}/network_1/ppo_head_0"
    out = _dense(g, f"{head}/policy_fc", x, network.action_head)
    policy = OUTPUT_NODES["clipped_ppo"]
    if spec.action_kind == "discrete":
        g.op(policy, "Softmax", out)
    else:
        low = g.op(f"{head}/clip_low", "Maximum", out, g.const(f"{head}/low", np.float32(-1.0)))
        g.op(policy, "Minimum", low, g.const(f"{head}/high", np.float32(1.0)))
    return bytes(g)


def _camera(
    g: GraphWriter, scope: str, x: str, encoder: nn.Sequential, shape: tuple[int, ...]
) -> str:
    """The camera encoder in NHWC: /255, 2x2 average pool, VALID convolutions with ReLU,
    flatten, a dense layer with ReLU (the layers of `sim.training.policy`)."""
    out = g.op(f"{scope}/scaled", "RealDiv", x, g.const(f"{scope}/scale", np.float32(255.0)))
    pool = [1, CAMERA_POOL, CAMERA_POOL, 1]
    out = g.op(
        f"{scope}/AvgPool",
        "AvgPool",
        out,
        ksize=attr_ints(pool),
        strides=attr_ints(pool),
        padding=attr_s("VALID"),
        data_format=attr_s("NHWC"),
    )
    height, width, channels = shape[0] // CAMERA_POOL, shape[1] // CAMERA_POOL, shape[2]
    convs = [layer for layer in encoder if isinstance(layer, nn.Conv2d)]
    for index, conv in enumerate(convs):
        name = f"{scope}/Conv2d_{index}"
        stride = int(conv.stride[0])
        kernel = g.const(f"{name}/kernel", _numpy(conv.weight).transpose(2, 3, 1, 0))  # HWIO
        out = g.op(
            f"{name}/Conv2D",
            "Conv2D",
            out,
            kernel,
            strides=attr_ints([1, stride, stride, 1]),
            padding=attr_s("VALID"),
            data_format=attr_s("NHWC"),
            dilations=attr_ints([1, 1, 1, 1]),
            use_cudnn_on_gpu=attr_b(True),
        )
        out = g.op(
            f"{name}/BiasAdd", "BiasAdd", out, _bias(g, name, conv), data_format=attr_s("NHWC")
        )
        out = g.op(f"{name}/Relu", "Relu", out)
        size = int(conv.kernel_size[0])
        height, width = (height - size) // stride + 1, (width - size) // stride + 1
        channels = conv.out_channels
    flat = height * width * channels
    target = g.const(f"{scope}/Flatten/shape", np.array([-1, flat], np.int32))
    out = g.op(f"{scope}/Flatten/Reshape", "Reshape", out, target, Tshape=attr_type(np.int32))
    (linear,) = [layer for layer in encoder if isinstance(layer, nn.Linear)]
    # torch's Flatten ordered the features (C, H, W); TensorFlow's Reshape gives (H, W, C).
    weight = _numpy(linear.weight).reshape(-1, channels, height, width)
    reordered = weight.transpose(0, 2, 3, 1).reshape(-1, flat)
    out = _matmul_bias(g, f"{scope}/Dense_0", out, reordered, _numpy(linear.bias))
    return g.op(f"{scope}/Dense_0/Relu", "Relu", out)


def _dense(g: GraphWriter, scope: str, x: str, layer: nn.Linear) -> str:
    return _matmul_bias(g, scope, x, _numpy(layer.weight), _numpy(layer.bias))


def _matmul_bias(g: GraphWriter, scope: str, x: str, weight: np.ndarray, bias: np.ndarray) -> str:
    """x @ weight.T + bias, as tf.layers.dense writes it (kernel [in, out])."""
    kernel = g.const(f"{scope}/kernel", np.ascontiguousarray(weight.T))
    out = g.op(
        f"{scope}/MatMul",
        "MatMul",
        x,
        kernel,
        transpose_a=attr_b(False),
        transpose_b=attr_b(False),
    )
    return g.op(
        f"{scope}/BiasAdd",
        "BiasAdd",
        out,
        g.const(f"{scope}/bias", bias),
        data_format=attr_s("NHWC"),
    )


def _bias(g: GraphWriter, scope: str, conv: nn.Conv2d) -> str:
    assert conv.bias is not None
    return g.const(f"{scope}/bias", _numpy(conv.bias))


def _numpy(tensor: torch.Tensor) -> np.ndarray:
    return np.ascontiguousarray(tensor.detach().to(torch.float32).numpy())

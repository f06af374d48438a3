"""Test helpers: write small GraphDefs and car archives by hand.

The encoder is the export's own (`sim.car_export.graph_writer`, protobuf's wire format with
TensorFlow's field numbers), so the tests can build graphs with any op, attribute or
corruption without TensorFlow.
"""

from __future__ import annotations

import io
import json
import tarfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from sim.car_export.graph_writer import (
    GraphWriter,
    attr_b,
    attr_f,
    attr_i,
    attr_ints,
    attr_s,
    attr_type,
    bytes_field,
    node_proto,
    varint,
)

__all__ = [
    "CAMERA_INPUT",
    "METADATA",
    "POLICY_OUTPUT",
    "GraphWriter",
    "attr_b",
    "attr_f",
    "attr_i",
    "attr_ints",
    "attr_s",
    "attr_type",
    "bytes_field",
    "camera_policy_graph",
    "flatten",
    "node_proto",
    "one_sentence",
    "varint",
    "write_archive",
]

CAMERA_INPUT = "main_level/agent/main/online/network_0/FRONT_FACING_CAMERA/FRONT_FACING_CAMERA"
POLICY_OUTPUT = "main_level/agent/main/online/network_1/ppo_head_0/policy"


def one_sentence(message: str) -> bool:
    """A user error as the design wants it: one sentence, ending with a full stop."""
    body = message.rstrip(".")
    return message.endswith(".") and ". " not in body and "\n" not in message


def camera_policy_graph(actions: int = 3, seed: int = 0) -> bytes:
    """A tiny DeepRacer-shaped camera policy: the car's input and output names, /255, one
    SAME convolution, max pooling, tf.layers' Flatten, a dense layer and a softmax."""
    rng = np.random.default_rng(seed)
    g = GraphWriter()
    x = g.placeholder(CAMERA_INPUT, [-1, 120, 160, 1])
    scaled = g.op("scaled", "RealDiv", x, g.const("scale", np.float32(255.0)))
    kernel = g.const("kernel", rng.normal(0.0, 0.3, (5, 5, 1, 4)).astype(np.float32))
    conv = g.op(
        "conv",
        "Conv2D",
        scaled,
        kernel,
        strides=attr_ints([1, 4, 4, 1]),
        padding=attr_s("SAME"),
        data_format=attr_s("NHWC"),
    )
    relu = g.op("relu", "Relu", g.op("bias", "BiasAdd", conv, g.const("b", np.full(4, 0.1))))
    pool = g.op(
        "pool",
        "MaxPool",
        relu,
        ksize=attr_ints([1, 3, 3, 1]),
        strides=attr_ints([1, 2, 2, 1]),
        padding=attr_s("SAME"),
    )
    flat = flatten(g, "flatten", pool)
    weights = g.const("w", rng.normal(0.0, 0.05, (15 * 20 * 4, actions)).astype(np.float32))
    logits = g.op("logits", "MatMul", flat, weights)
    g.op(POLICY_OUTPUT, "Softmax", logits)
    return bytes(g)


def flatten(g: GraphWriter, name: str, x: str) -> str:
    """tf.layers' Flatten as TensorFlow 1 writes it: Shape, StridedSlice, Pack, Reshape."""
    shape = g.op(f"{name}/Shape", "Shape", x, out_type=attr_type(np.int32))
    batch = g.op(
        f"{name}/batch",
        "StridedSlice",
        shape,
        g.const(f"{name}/begin", np.array([0], np.int32)),
        g.const(f"{name}/end", np.array([1], np.int32)),
        g.const(f"{name}/step", np.array([1], np.int32)),
        shrink_axis_mask=attr_i(1),
        T=attr_type(np.int32),
    )
    target = g.op(
        f"{name}/target",
        "Pack",
        batch,
        g.const(f"{name}/rest", np.int32(-1)),
        axis=attr_i(0),
        T=attr_type(np.int32),
    )
    return g.op(f"{name}/Reshape", "Reshape", x, target)


METADATA = {
    "action_space": [
        {"steering_angle": -30, "speed": 1.0},
        {"steering_angle": 0, "speed": 2.0},
        {"steering_angle": 30, "speed": 1.0},
    ],
    "sensor": ["FRONT_FACING_CAMERA"],
    "neural_network": "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW",
    "training_algorithm": "clipped_ppo",
    "action_space_type": "discrete",
    "version": "5",
}


def write_archive(
    path: Path,
    members: Mapping[str, bytes] | None = None,
    *,
    graph: bytes | None = None,
    metadata: Mapping[str, Any] | None = None,
    links: Mapping[str, str] | None = None,
    directories: Iterable[str] = (),
) -> Path:
    """A car archive at `path`: the two members unless `members` gives others."""
    if members is None:
        members = {
            "model_metadata.json": json.dumps(metadata or METADATA).encode(),
            "agent/model.pb": camera_policy_graph() if graph is None else graph,
        }
    with tarfile.open(path, "w:gz") as tar:
        for name in directories:
            info = tarfile.TarInfo(name)
            info.type = tarfile.DIRTYPE
            tar.addfile(info)
        for name, data in members.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
        for name, target in (links or {}).items():
            info = tarfile.TarInfo(name)
            info.type = tarfile.SYMTYPE
            info.linkname = target
            tar.addfile(info)
    return path

"""Test helpers: write small GraphDefs and car archives by hand.

The encoder writes protobuf's wire format with the field numbers of TensorFlow's .proto
files (see sim.car_export.graph_def), so the tests can build graphs with any op, attribute
or corruption without TensorFlow.
"""

from __future__ import annotations

import io
import json
import struct
import tarfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

TF_TYPES = {
    np.dtype(np.float32): 1,
    np.dtype(np.float64): 2,
    np.dtype(np.int32): 3,
    np.dtype(np.uint8): 4,
    np.dtype(np.int64): 9,
    np.dtype(np.bool_): 10,
}

CAMERA_INPUT = "main_level/agent/main/online/network_0/FRONT_FACING_CAMERA/FRONT_FACING_CAMERA"
POLICY_OUTPUT = "main_level/agent/main/online/network_1/ppo_head_0/policy"


def one_sentence(message: str) -> bool:
    """A user error as the design wants it: one sentence, ending with a full stop."""
    body = message.rstrip(".")
    return message.endswith(".") and ". " not in body and "\n" not in message


def varint(value: int) -> bytes:
    value &= (1 << 64) - 1  # negatives as 64-bit two's complement, as protobuf writes int64
    out = bytearray()
    while True:
        low = value & 0x7F
        value >>= 7
        if value:
            out.append(low | 0x80)
        else:
            out.append(low)
            return bytes(out)


def number_field(number: int, value: int) -> bytes:
    return varint(number << 3) + varint(value)


def bytes_field(number: int, payload: bytes) -> bytes:
    return varint(number << 3 | 2) + varint(len(payload)) + payload


def float_field(number: int, value: float) -> bytes:
    return varint(number << 3 | 5) + struct.pack("<f", value)


def shape_proto(shape: Sequence[int]) -> bytes:
    return b"".join(bytes_field(2, number_field(1, size)) for size in shape)


def tensor_proto(array: np.ndarray, packed_values: bool = False) -> bytes:
    array = np.asarray(array)
    out = number_field(1, TF_TYPES[array.dtype]) + bytes_field(2, shape_proto(array.shape))
    if not packed_values:
        return out + bytes_field(4, array.astype(array.dtype.newbyteorder("<")).tobytes())
    flat = array.reshape(-1)
    if array.dtype == np.float32:
        return out + bytes_field(5, flat.astype("<f4").tobytes())
    return out + bytes_field(7, b"".join(varint(int(v)) for v in flat))


# AttrValue: one encoder per kind (field numbers from attr_value.proto).
def attr_s(text: str) -> bytes:
    return bytes_field(2, text.encode())


def attr_i(value: int) -> bytes:
    return number_field(3, value)


def attr_f(value: float) -> bytes:
    return float_field(4, value)


def attr_b(value: bool) -> bytes:
    return number_field(5, int(value))


def attr_type(dtype: Any) -> bytes:
    return number_field(6, TF_TYPES[np.dtype(dtype)])


def attr_shape(shape: Sequence[int]) -> bytes:
    return bytes_field(7, shape_proto(shape))


def attr_tensor(array: np.ndarray, packed_values: bool = False) -> bytes:
    return bytes_field(8, tensor_proto(array, packed_values))


def attr_ints(values: Sequence[int]) -> bytes:
    return bytes_field(1, bytes_field(3, b"".join(varint(v) for v in values)))


def node_proto(
    name: str, op: str, inputs: Iterable[str] = (), attrs: Mapping[str, bytes] | None = None
) -> bytes:
    out = bytes_field(1, name.encode()) + bytes_field(2, op.encode())
    for source in inputs:
        out += bytes_field(3, source.encode())
    for key, value in (attrs or {}).items():
        out += bytes_field(5, bytes_field(1, key.encode()) + bytes_field(2, value))
    return out


class GraphWriter:
    """Builds a GraphDef node by node; `bytes()` gives the serialized graph."""

    def __init__(self) -> None:
        self.nodes: list[bytes] = []

    def placeholder(self, name: str, shape: Sequence[int], dtype: Any = np.float32) -> str:
        attrs = {"dtype": attr_type(dtype), "shape": attr_shape(shape)}
        self.nodes.append(node_proto(name, "Placeholder", (), attrs))
        return name

    def const(self, name: str, value: Any, packed_values: bool = False) -> str:
        array = np.asarray(value)
        if array.dtype == np.float64:
            array = array.astype(np.float32)
        if array.dtype == np.int64:
            array = array.astype(np.int32)
        attrs = {"dtype": attr_type(array.dtype), "value": attr_tensor(array, packed_values)}
        self.nodes.append(node_proto(name, "Const", (), attrs))
        return name

    def op(self, name: str, op: str, *inputs: str, **attrs: bytes) -> str:
        attrs.setdefault("T", attr_type(np.float32))
        self.nodes.append(node_proto(name, op, inputs, attrs))
        return name

    def __bytes__(self) -> bytes:
        return b"".join(bytes_field(1, node) for node in self.nodes)


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

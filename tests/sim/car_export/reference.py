"""A second runtime for the tests: the same graphs, in float64 NumPy, written from
TensorFlow's documented semantics (NHWC, SAME padding with the odd pixel after) with loops
instead of torch's kernels, so the two implementations share nothing but the graph reader."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from sim.car_archive.graph_def import FrozenGraph, GraphNode, node_name


def run_reference(graph: FrozenGraph, output: str, feeds: Mapping[str, np.ndarray]) -> np.ndarray:
    values: dict[str, Any] = {}
    for node in graph.plan([output]):
        args = [values[node_name(source)] for source in node.inputs]
        values[node.name] = _op(node, args, feeds)
    return np.asarray(values[output])


def _same(extent: int, k: int, stride: int, dilation: int) -> tuple[int, int]:
    span = (k - 1) * dilation + 1
    total = max((math.ceil(extent / stride) - 1) * stride + span - extent, 0)
    return total // 2, total - total // 2


def _pad(node: GraphNode, x: np.ndarray, window: tuple[int, int], fill: float) -> np.ndarray:
    strides = node.ints("strides")
    dilations = node.ints("dilations", (1, 1, 1, 1))
    if node.text("padding") != "SAME":
        return x
    pads = [
        _same(x.shape[axis], window[axis - 1], strides[axis], dilations[axis]) for axis in (1, 2)
    ]
    return np.pad(x, [(0, 0), pads[0], pads[1], (0, 0)], constant_values=fill)


def _conv(node: GraphNode, x: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    kh, kw = kernel.shape[:2]
    x = _pad(node, x, (kh, kw), 0.0)
    _, sh, sw, _ = node.ints("strides")
    _, dh, dw, _ = node.ints("dilations", (1, 1, 1, 1))
    oh = (x.shape[1] - (kh - 1) * dh - 1) // sh + 1
    ow = (x.shape[2] - (kw - 1) * dw - 1) // sw + 1
    out = np.zeros((x.shape[0], oh, ow, kernel.shape[3]))
    for i in range(kh):
        for j in range(kw):
            patch = x[:, i * dh : i * dh + sh * (oh - 1) + 1 : sh,
                      j * dw : j * dw + sw * (ow - 1) + 1 : sw, :]  # fmt: skip
            out += patch @ kernel[i, j]
    return out


def _max_pool(node: GraphNode, x: np.ndarray) -> np.ndarray:
    _, kh, kw, _ = node.ints("ksize")
    _, sh, sw, _ = node.ints("strides")
    x = _pad(node, x, (kh, kw), -np.inf)
    oh = (x.shape[1] - kh) // sh + 1
    ow = (x.shape[2] - kw) // sw + 1
    out = np.full((x.shape[0], oh, ow, x.shape[3]), -np.inf)
    for i in range(kh):
        for j in range(kw):
            out = np.maximum(
                out, x[:, i : i + sh * (oh - 1) + 1 : sh, j : j + sw * (ow - 1) + 1 : sw]
            )
    return out


def _op(node: GraphNode, args: list[Any], feeds: Mapping[str, np.ndarray]) -> Any:
    op = node.op
    if op == "Placeholder":
        return np.asarray(feeds[node.name], dtype=np.float64)
    if op == "Const":
        value = node.constant()
        return value.astype(np.float64) if value.dtype.kind == "f" else value
    if op in ("Identity", "StopGradient"):
        return args[0]
    binary = {
        "Add": np.add, "AddV2": np.add, "Sub": np.subtract, "Mul": np.multiply,
        "RealDiv": np.divide, "Maximum": np.maximum, "Minimum": np.minimum,
    }  # fmt: skip
    if op in binary:
        return binary[op](args[0], args[1])
    if op == "Conv2D":
        return _conv(node, args[0], args[1])
    if op == "MaxPool":
        return _max_pool(node, args[0])
    if op == "BiasAdd":
        return args[0] + args[1]
    if op == "Relu":
        return np.maximum(args[0], 0.0)
    if op == "Tanh":
        return np.tanh(args[0])
    if op == "Softmax":
        shifted = np.exp(args[0] - args[0].max(axis=-1, keepdims=True))
        return shifted / shifted.sum(axis=-1, keepdims=True)
    if op == "MatMul":
        a = args[0].T if node.flag("transpose_a") else args[0]
        b = args[1].T if node.flag("transpose_b") else args[1]
        return a @ b
    if op == "Shape":
        return np.array(args[0].shape, dtype=np.int32)
    if op == "StridedSlice":  # the forms tf.layers writes: one axis, optionally shrunk
        begin, end, step = (int(v[0]) for v in args[1:])
        if node.integer("shrink_axis_mask", 0) & 1:
            return args[0][begin]
        return args[0][begin:end:step]
    if op == "Pack":
        return np.stack([np.asarray(a) for a in args], axis=node.integer("axis", 0))
    if op == "Reshape":
        return args[0].reshape([int(v) for v in np.asarray(args[1]).reshape(-1)])
    raise NotImplementedError(op)

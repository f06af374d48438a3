"""Runs a frozen TensorFlow graph (`sim.car_archive.graph_def`) with torch on the CPU.

Tensors keep TensorFlow's layout (NHWC) between ops, so Reshape and Flatten see the
element order TensorFlow would; only Conv2D and the pools turn to torch's NCHW and back.
Padding follows TensorFlow: VALID, EXPLICIT, and SAME with the odd pixel after (bottom,
right), not torch's symmetric padding. Nodes whose inputs are all constants are computed
once when the runner is made (a frozen graph's `kernel/read` Identities, for example).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray
from torch.nn import functional

from sim.car_archive.errors import CarModelError
from sim.car_archive.graph_def import FrozenGraph, GraphNode, node_name, output_index

Tensor = torch.Tensor
OpFunction = Callable[[GraphNode, list[Tensor]], Tensor]

_TORCH_DTYPES: dict[str, torch.dtype] = {
    "float16": torch.float16,
    "float32": torch.float32,
    "float64": torch.float64,
    "int8": torch.int8,
    "int16": torch.int16,
    "int32": torch.int32,
    "int64": torch.int64,
    "uint8": torch.uint8,
    "bool": torch.bool,
}


class GraphRunner:
    """Computes `output` of `graph` from its Placeholders, fed by name."""

    def __init__(self, graph: FrozenGraph, output: str) -> None:
        self.output = output
        self._plan = graph.plan([output])
        self.inputs = tuple(node.name for node in self._plan if node.op == "Placeholder")
        self._constants: dict[str, Tensor] = {}
        with torch.inference_mode():
            for node in self._plan:
                if node.op == "Const":
                    self._constants[node.name] = _constant(node)
                elif _foldable(node, self._constants):
                    self._constants[node.name] = self._compute(node, self._constants)
        self._steps = [node for node in self._plan if node.name not in self._constants]

    def run(self, feeds: Mapping[str, NDArray[Any]]) -> NDArray[Any]:
        """The output for these Placeholder values (arrays, cast to each one's dtype)."""
        missing = [name for name in self.inputs if name not in feeds]
        if missing:
            raise CarModelError(f"the graph needs a value for its input {missing[0]!r}.")
        values: dict[str, Tensor] = dict(self._constants)
        with torch.inference_mode():
            for node in self._steps:
                if node.op == "Placeholder":
                    values[node.name] = _placeholder(node, feeds[node.name])
                else:
                    values[node.name] = self._compute(node, values)
            return values[self.output].numpy()

    def _compute(self, node: GraphNode, values: Mapping[str, Tensor]) -> Tensor:
        args = []
        for source in node.inputs:
            if output_index(source) != 0:
                raise CarModelError(
                    f"node {node.name!r} reads output {output_index(source)} of another "
                    "node; racer-tui computes only first outputs."
                )
            args.append(values[node_name(source)])
        op = OPS.get(node.op)
        if op is None:  # NoOp, asked for as an output
            raise CarModelError(f"node {node.name!r} ({node.op}) computes no value.")
        return op(node, args)


def _foldable(node: GraphNode, constants: Mapping[str, Tensor]) -> bool:
    # Shape is left to run time: the batch size is only known then.
    return (
        node.op not in ("Placeholder", "Shape", "NoOp")
        and bool(node.inputs)
        and all(name in constants for name in node.inputs)
    )


def _constant(node: GraphNode) -> Tensor:
    # A copy: frombuffer views of the file are read-only and torch wants writable memory.
    return torch.from_numpy(np.array(node.constant(), copy=True))


def _placeholder(node: GraphNode, value: NDArray[Any]) -> Tensor:
    dtype = node.dtype("dtype")
    array = np.ascontiguousarray(value, dtype=dtype)
    shape = node.attrs["shape"].shape if "shape" in node.attrs else None
    if shape is not None and (
        len(shape) != array.ndim
        or any(want not in (-1, got) for want, got in zip(shape, array.shape, strict=True))
    ):
        wanted = ["?" if size < 0 else size for size in shape]
        raise CarModelError(f"input {node.name!r} takes shape {wanted}, not {list(array.shape)}.")
    return torch.from_numpy(array)


def _torch_dtype(node: GraphNode, key: str) -> torch.dtype:
    return _TORCH_DTYPES[node.dtype(key).name]


def _nhwc(node: GraphNode) -> None:
    layout = node.text("data_format", "NHWC")
    if layout != "NHWC":
        raise CarModelError(
            f"node {node.name!r} ({node.op}) uses data_format {layout}; racer-tui runs NHWC."
        )


def _padding(
    node: GraphNode,
    size: Sequence[int],
    window: Sequence[int],
    strides: Sequence[int],
    dilations: Sequence[int],
) -> list[int]:
    """(top, bottom, left, right) for TensorFlow's padding of a 2-D window."""
    mode = node.text("padding")
    if mode == "VALID":
        return [0, 0, 0, 0]
    if mode == "EXPLICIT":
        pads = node.ints("explicit_paddings")
        if len(pads) != 8 or any(pads[:2]) or any(pads[6:]):
            raise CarModelError(f"node {node.name!r} pads other than its height and width.")
        return list(pads[2:6])
    if mode != "SAME":
        raise CarModelError(f"node {node.name!r} has unknown padding {mode!r}.")
    out: list[int] = []
    for extent, k, stride, dilation in zip(size, window, strides, dilations, strict=True):
        span = (k - 1) * dilation + 1
        total = max((math.ceil(extent / stride) - 1) * stride + span - extent, 0)
        out += [total // 2, total - total // 2]  # the odd pixel goes after
    return out


def _spatial(node: GraphNode, key: str, default: tuple[int, ...] | None = None) -> list[int]:
    """The height and width entries of an NHWC attribute list (strides, ksize, dilations)."""
    values = node.ints(key, default)
    if len(values) != 4 or values[0] != 1 or values[3] != 1:
        raise CarModelError(f"node {node.name!r} has {key} {list(values)}; only H and W may vary.")
    return [values[1], values[2]]


def _conv2d(node: GraphNode, args: list[Tensor]) -> Tensor:
    _nhwc(node)
    x, kernel = args  # NHWC, and HWIO
    strides = _spatial(node, "strides")
    dilations = _spatial(node, "dilations", (1, 1, 1, 1))
    top, bottom, left, right = _padding(node, x.shape[1:3], kernel.shape[:2], strides, dilations)
    image = functional.pad(x.permute(0, 3, 1, 2), (left, right, top, bottom))
    weight = kernel.permute(3, 2, 0, 1)  # OIHW
    groups = x.shape[3] // kernel.shape[2]
    out = functional.conv2d(image, weight, stride=strides, dilation=dilations, groups=groups)
    return out.permute(0, 2, 3, 1)


def _max_pool(node: GraphNode, args: list[Tensor]) -> Tensor:
    _nhwc(node)
    (x,) = args
    window = _spatial(node, "ksize")
    strides = _spatial(node, "strides")
    top, bottom, left, right = _padding(node, x.shape[1:3], window, strides, [1, 1])
    # SAME max pooling never picks a padded cell: pad with -inf, not zeros.
    image = functional.pad(x.permute(0, 3, 1, 2), (left, right, top, bottom), value=-math.inf)
    return functional.max_pool2d(image, window, strides).permute(0, 2, 3, 1)


def _avg_pool(node: GraphNode, args: list[Tensor]) -> Tensor:
    _nhwc(node)
    (x,) = args
    window = _spatial(node, "ksize")
    strides = _spatial(node, "strides")
    top, bottom, left, right = _padding(node, x.shape[1:3], window, strides, [1, 1])
    image = functional.pad(x.permute(0, 3, 1, 2), (left, right, top, bottom))
    total = functional.avg_pool2d(image, window, strides, divisor_override=1)
    # SAME average pooling divides by the cells inside the image, not the window's size.
    inside = functional.pad(
        torch.ones_like(x[:1, :, :, :1]).permute(0, 3, 1, 2), (left, right, top, bottom)
    )
    count = functional.avg_pool2d(inside, window, strides, divisor_override=1)
    return (total / count).permute(0, 2, 3, 1)


def _bias_add(node: GraphNode, args: list[Tensor]) -> Tensor:
    _nhwc(node)
    return args[0] + args[1]


def _mat_mul(node: GraphNode, args: list[Tensor]) -> Tensor:
    a, b = args
    if node.flag("transpose_a"):
        a = a.transpose(0, 1)
    if node.flag("transpose_b"):
        b = b.transpose(0, 1)
    return a @ b


def _batch_norm(node: GraphNode, args: list[Tensor]) -> Tensor:
    _nhwc(node)
    if node.flag("is_training"):
        raise CarModelError(f"node {node.name!r} normalises in training mode, not inference.")
    x, scale, offset, mean, variance = args
    epsilon = node.attrs["epsilon"].f if "epsilon" in node.attrs else None
    factor = scale * torch.rsqrt(variance + (1e-4 if epsilon is None else epsilon))
    return x * factor + (offset - mean * factor)


def _strided_slice(node: GraphNode, args: list[Tensor]) -> Tensor:
    x, begin, end, strides = args[0], args[1].tolist(), args[2].tolist(), args[3].tolist()
    masks = {key: node.integer(key, 0) for key in _SLICE_MASKS}
    index: list[Any] = []
    for k, (first, last, step) in enumerate(zip(begin, end, strides, strict=True)):
        bit = 1 << k
        if masks["ellipsis_mask"] & bit:
            index.append(Ellipsis)
        elif masks["new_axis_mask"] & bit:
            index.append(None)
        elif masks["shrink_axis_mask"] & bit:
            index.append(int(first))
        else:
            if step <= 0:
                raise CarModelError(f"node {node.name!r} slices backwards, which is not supported.")
            start = None if masks["begin_mask"] & bit else int(first)
            stop = None if masks["end_mask"] & bit else int(last)
            index.append(slice(start, stop, int(step)))
    return x[tuple(index)]


_SLICE_MASKS = ("begin_mask", "end_mask", "ellipsis_mask", "new_axis_mask", "shrink_axis_mask")


def _axis(value: int, rank: int) -> int:
    return value + rank if value < 0 else value


def _pack(node: GraphNode, args: list[Tensor]) -> Tensor:
    return torch.stack(args, dim=_axis(node.integer("axis", 0), args[0].dim() + 1))


def _concat(node: GraphNode, args: list[Tensor]) -> Tensor:
    *parts, axis = args
    return torch.cat(parts, dim=_axis(int(axis), parts[0].dim()))


def _reshape(node: GraphNode, args: list[Tensor]) -> Tensor:
    x, shape = args
    return x.reshape([int(size) for size in shape.reshape(-1).tolist()])


def _squeeze(node: GraphNode, args: list[Tensor]) -> Tensor:
    (x,) = args
    dims = node.ints("squeeze_dims", ())
    if not dims:
        return x.squeeze()
    kept = [size for k, size in enumerate(x.shape) if k not in {_axis(d, x.dim()) for d in dims}]
    return x.reshape(kept)


def _expand_dims(node: GraphNode, args: list[Tensor]) -> Tensor:
    x, axis = args
    return x.unsqueeze(_axis(int(axis), x.dim() + 1))


def _shape(node: GraphNode, args: list[Tensor]) -> Tensor:
    dtype = _torch_dtype(node, "out_type") if "out_type" in node.attrs else torch.int32
    return torch.tensor(list(args[0].shape), dtype=dtype)


def _cast(node: GraphNode, args: list[Tensor]) -> Tensor:
    return args[0].to(_torch_dtype(node, "DstT"))


def _unary(function: Callable[[Tensor], Tensor]) -> OpFunction:
    return lambda node, args: function(args[0])


def _binary(function: Callable[[Tensor, Tensor], Tensor]) -> OpFunction:
    return lambda node, args: function(args[0], args[1])


OPS: dict[str, OpFunction] = {
    "Identity": _unary(lambda x: x),
    "StopGradient": _unary(lambda x: x),
    "Add": _binary(torch.add),
    "AddV2": _binary(torch.add),
    "Maximum": _binary(torch.maximum),
    "Minimum": _binary(torch.minimum),
    "Mul": _binary(torch.mul),
    "RealDiv": _binary(torch.div),
    "Rsqrt": _unary(torch.rsqrt),
    "Sub": _binary(torch.sub),
    "AvgPool": _avg_pool,
    "BiasAdd": _bias_add,
    "Conv2D": _conv2d,
    "FusedBatchNorm": _batch_norm,
    "FusedBatchNormV3": _batch_norm,
    "MatMul": _mat_mul,
    "MaxPool": _max_pool,
    "Relu": _unary(torch.relu),
    "Sigmoid": _unary(torch.sigmoid),
    "Softmax": _unary(lambda x: torch.softmax(x, dim=-1)),
    "Tanh": _unary(torch.tanh),
    "Cast": _cast,
    "ConcatV2": _concat,
    "ExpandDims": _expand_dims,
    "Pack": _pack,
    "Reshape": _reshape,
    "Shape": _shape,
    "Squeeze": _squeeze,
    "StridedSlice": _strided_slice,
}
# Const and Placeholder are the runner's own; NoOp has no value. The graph reader's
# SUPPORTED_OPS must be exactly these (a test checks).
RUNNER_OPS = frozenset({*OPS, "Const", "Placeholder", "NoOp"})

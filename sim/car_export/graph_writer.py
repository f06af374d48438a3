"""Writing a frozen TensorFlow graph (`GraphDef`) without TensorFlow: protobuf's wire format
by hand, with the field numbers `sim.car_archive.graph_def` reads (TensorFlow's public .proto
files). The export for the car builds its graph with `GraphWriter`; the tests build graphs
of any shape (and any corruption) with the same pieces.

Only what a frozen inference graph needs is written: nodes with their name, op, inputs and
attributes; no versions, devices or function library (TensorFlow and OpenVINO default them,
and DeepRacer's own frozen graphs leave them out too).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

# DataType enum values (types.proto).
TF_TYPES = {
    np.dtype(np.float32): 1,
    np.dtype(np.float64): 2,
    np.dtype(np.int32): 3,
    np.dtype(np.uint8): 4,
    np.dtype(np.int64): 9,
    np.dtype(np.bool_): 10,
}


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

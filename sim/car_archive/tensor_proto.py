"""TensorFlow's TensorProto and TensorShapeProto (tensor.proto, tensor_shape.proto) read from
protobuf's wire format: the constants of a frozen graph as NumPy arrays.

TensorProto: dtype = 1, tensor_shape = 2, tensor_content = 4 (raw little-endian bytes), or
typed value lists (float_val = 5, double_val = 6, int_val = 7, int64_val = 10, bool_val = 11,
half_val = 13); a list shorter than the shape is filled with its last value, as TensorFlow
does. TensorShapeProto: dim = 2 (Dim.size = 1), unknown_rank = 3.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.car_archive.errors import CarModelError
from sim.car_archive.protobuf_wire import (
    FIXED32,
    FIXED64,
    LENGTH_DELIMITED,
    WireFormatError,
    as_bytes,
    as_int,
    fields,
    packed_varints,
)

# TensorFlow's DataType numbers (types.proto) for the tensors a policy graph holds.
DTYPES: dict[int, np.dtype[Any]] = {
    1: np.dtype(np.float32),
    2: np.dtype(np.float64),
    3: np.dtype(np.int32),
    4: np.dtype(np.uint8),
    5: np.dtype(np.int16),
    6: np.dtype(np.int8),
    9: np.dtype(np.int64),
    10: np.dtype(np.bool_),
    19: np.dtype(np.float16),
}

# A constant given as one repeated value fills its whole shape, so a few bytes of file could
# ask for gigabytes: cap the elements a constant may expand to (256 MB of float32).
MAX_EXPANDED_ELEMENTS = 1 << 26


class ExpansionBudget:
    """How many values one graph's constants may still expand to from short value lists."""

    def __init__(self, limit: int = MAX_EXPANDED_ELEMENTS) -> None:
        self.left = limit


def read_shape(data: memoryview) -> tuple[int, ...]:
    """A TensorShapeProto's dimensions (-1 for an unknown size)."""
    dims: list[int] = []
    for number, _, value in fields(data):
        if number == 2:
            size = -1
            for dim_number, _, dim_value in fields(as_bytes(value, "a shape dimension")):
                if dim_number == 1:
                    size = as_int(dim_value, "a dimension size")
            dims.append(size)
        elif number == 3 and as_int(value, "unknown_rank"):
            raise CarModelError("a shape has unknown rank, which a frozen policy never needs.")
    return tuple(dims)


def read_floats(wire: int, value: int | memoryview, dtype: str) -> NDArray[Any]:
    """A repeated float or double field: packed (one run of bytes) or one fixed value."""
    if wire not in (LENGTH_DELIMITED, FIXED32, FIXED64) or not isinstance(value, memoryview):
        raise WireFormatError("a float list is stored as a number (corrupt file).")
    item = np.dtype(dtype).itemsize
    if len(value) % item:
        raise WireFormatError("a float list's length is not a whole number of values.")
    return np.frombuffer(value, dtype=dtype)


# TensorProto's typed value fields: field number -> how its values are stored.
_FLOAT_FIELDS = {5: "<f4", 6: "<f8"}
_INT_FIELDS = (7, 10, 11, 13)  # int_val, int64_val, bool_val, half_val


def read_tensor(data: memoryview, budget: ExpansionBudget) -> NDArray[Any]:
    """A TensorProto as an array: from its raw content, or from its typed value lists."""
    dtype_number = 0
    shape: tuple[int, ...] = ()
    content: memoryview | None = None
    floats: list[NDArray[Any]] = []
    ints: list[int] = []
    for number, wire, value in fields(data):
        if number == 1:
            dtype_number = as_int(value, "a tensor's type")
        elif number == 2:
            shape = read_shape(as_bytes(value, "a tensor's shape"))
        elif number == 4:
            content = as_bytes(value, "a tensor's content")
        elif number in _FLOAT_FIELDS:
            floats.append(read_floats(wire, value, _FLOAT_FIELDS[number]))
        elif number in _INT_FIELDS:
            ints.extend(packed_varints(value))
        elif number in (8, 9, 12, 14, 15, 16, 17):
            raise CarModelError(
                "a constant holds strings, complex numbers, resources or unsigned integers."
            )
    dtype = DTYPES.get(dtype_number)
    if dtype is None:
        raise CarModelError(f"a constant has TensorFlow data type {dtype_number}, not a number.")
    if any(size < 0 for size in shape):
        raise CarModelError("a constant has a dimension of unknown size.")
    count = int(np.prod(shape, dtype=np.int64)) if shape else 1
    if content is not None and len(content) > 0:
        if len(content) != count * dtype.itemsize:
            raise CarModelError(
                f"a constant of shape {list(shape)} holds {len(content):,} bytes, "
                f"not the {count * dtype.itemsize:,} its shape needs."
            )
        # Little-endian on the wire, as every machine TensorFlow writes graphs on.
        return np.frombuffer(content, dtype=dtype.newbyteorder("<")).astype(dtype).reshape(shape)
    if count > budget.left:
        raise CarModelError(
            f"a constant of shape {list(shape)} would fill more than "
            f"{MAX_EXPANDED_ELEMENTS:,} values from a short list."
        )
    budget.left -= count
    if dtype_number == 19:  # half_val carries float16 bit patterns in int32s
        given = np.array(ints, dtype=np.uint16).view(np.float16)
    elif floats:
        given = np.concatenate(floats).astype(dtype)
    else:
        given = np.array(ints, dtype=np.int64).astype(dtype)
    if given.size > count:
        raise CarModelError(f"a constant of shape {list(shape)} lists {given.size:,} values.")
    # TensorFlow fills the rest of the shape with the last value given (zeros if none).
    out = np.zeros(count, dtype=dtype) if given.size == 0 else np.full(count, given[-1], dtype)
    out[: given.size] = given
    return out.reshape(shape)

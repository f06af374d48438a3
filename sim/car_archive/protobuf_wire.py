"""Protocol Buffers' wire format, read by hand: enough to walk a TensorFlow GraphDef.

A frozen graph is untrusted bytes from an archive. Decoding the wire format directly keeps
the reader small and free of generated code: every field is a (number, wire type, value)
triple, and the schema (which number means what) lives with the caller in `graph_def`.
Every length is checked against the bytes left, so a truncated or hostile file ends in one
`WireFormatError` sentence instead of an IndexError or a huge allocation.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator

from sim.car_archive.errors import CarModelError

VARINT = 0
FIXED64 = 1
LENGTH_DELIMITED = 2
FIXED32 = 5

_MAX_VARINT_BYTES = 10  # a 64-bit value in 7-bit groups
_UINT64 = 1 << 64


class WireFormatError(CarModelError):
    """The bytes are not a well-formed protobuf message."""


Field = tuple[int, int, "int | memoryview"]


def read_varint(data: memoryview, pos: int) -> tuple[int, int]:
    """The unsigned varint at `pos` and the position after it."""
    result = 0
    shift = 0
    end = min(len(data), pos + _MAX_VARINT_BYTES)
    while pos < end:
        byte = data[pos]
        pos += 1
        result |= (byte & 0x7F) << shift
        if byte < 0x80:
            return result, pos
        shift += 7
    if pos >= len(data):
        raise WireFormatError("the data ends in the middle of a number (truncated file).")
    raise WireFormatError("a number is longer than 10 bytes (corrupt file).")


def signed64(value: int) -> int:
    """A varint's value as protobuf's int64 (and int32: negatives are sign-extended to 64 bits)."""
    return value - _UINT64 if value >= 1 << 63 else value


def fields(data: memoryview) -> Iterator[Field]:
    """Each field of one message in order: (field number, wire type, value). Varints come
    as unsigned ints; fixed-width and length-delimited values as views of their bytes."""
    pos = 0
    size = len(data)
    while pos < size:
        key, pos = read_varint(data, pos)
        number, wire = key >> 3, key & 7
        if number == 0:
            raise WireFormatError("a field has number 0 (corrupt file).")
        if wire == VARINT:
            value, pos = read_varint(data, pos)
            yield number, wire, value
            continue
        if wire == LENGTH_DELIMITED:
            length, pos = read_varint(data, pos)
        elif wire == FIXED64:
            length = 8
        elif wire == FIXED32:
            length = 4
        else:  # 3 and 4 are proto2 groups, which TensorFlow's protos never use
            raise WireFormatError(f"field {number} has wire type {wire}, which is not supported.")
        if length > size - pos:
            raise WireFormatError(
                f"field {number} needs {length:,} bytes but only {size - pos:,} are left "
                "(truncated file)."
            )
        yield number, wire, data[pos : pos + length]
        pos += length


def as_float32(value: int | memoryview) -> float:
    """A `float` field (fixed32) as a Python float."""
    if not isinstance(value, memoryview) or len(value) != 4:
        raise WireFormatError("a float field is not 4 bytes long (corrupt file).")
    return float(struct.unpack("<f", value)[0])


def as_bytes(value: int | memoryview, what: str) -> memoryview:
    """A length-delimited field's bytes; `what` names the field in the error."""
    if not isinstance(value, memoryview):
        raise WireFormatError(f"{what} is a number where bytes were expected (corrupt file).")
    return value


def as_text(value: int | memoryview, what: str) -> str:
    """A `string` field as text (protobuf strings are UTF-8)."""
    try:
        return bytes(as_bytes(value, what)).decode("utf-8")
    except UnicodeDecodeError:
        raise WireFormatError(f"{what} is not UTF-8 text (corrupt file).") from None


def as_int(value: int | memoryview, what: str) -> int:
    """A varint field's value as a signed 64-bit integer."""
    if isinstance(value, memoryview):
        raise WireFormatError(f"{what} is bytes where a number was expected (corrupt file).")
    return signed64(value)


def packed_varints(value: int | memoryview) -> list[int]:
    """A repeated integer field's values: one varint, or a packed run of them."""
    if not isinstance(value, memoryview):
        return [signed64(value)]
    out: list[int] = []
    pos = 0
    while pos < len(value):
        number, pos = read_varint(value, pos)
        out.append(signed64(number))
    return out

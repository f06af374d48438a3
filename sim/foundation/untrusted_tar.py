"""Reading a `.tar.gz` that came from anyone, forwards only, nothing extracted blindly.

The two readers of such archives (a car archive, `sim.car_archive.archive`; a model's
download, `sim.garage.model_archive`) share what makes a member safe to read, and a stream
that stops decompressing past a limit so a small file cannot expand without bound. Each
says the problem in its own words: these raise `UnsafeMemberError` or call `on_exceeded`.
"""

from __future__ import annotations

import io
import tarfile
from collections.abc import Callable
from enum import StrEnum
from pathlib import PurePosixPath
from typing import Protocol


class Readable(Protocol):
    def read(self, size: int = -1, /) -> bytes: ...


class Unsafe(StrEnum):
    OUTSIDE = "outside"  # an absolute path, `..`, a backslash or a NUL in the name
    SPECIAL = "special"  # a link, a device, a FIFO


class UnsafeMemberError(Exception):
    def __init__(self, name: str, why: Unsafe) -> None:
        super().__init__(name)
        self.name = name
        self.why = why


def member_name(member: tarfile.TarInfo) -> str | None:
    """The member's name without a leading './', or None for a directory entry;
    `UnsafeMemberError` for a name that points outside the archive or a member that is not a
    plain file."""
    raw = member.name
    pure = PurePosixPath(raw)
    if raw.startswith("/") or "\\" in raw or "\x00" in raw or ".." in pure.parts:
        raise UnsafeMemberError(raw, Unsafe.OUTSIDE)
    if member.isdir():
        return None
    if not member.isreg():
        raise UnsafeMemberError(raw, Unsafe.SPECIAL)
    return "/".join(part for part in pure.parts if part != ".")


class CappedStream(io.RawIOBase):
    """A read-only stream that calls `on_exceeded` (which raises) once more than `limit`
    bytes have come out of `stream`."""

    def __init__(self, stream: Readable, limit: int, on_exceeded: Callable[[], None]) -> None:
        super().__init__()
        self._stream = stream
        self._left = limit
        self._on_exceeded = on_exceeded

    def readable(self) -> bool:
        return True

    def read(self, size: int = -1) -> bytes:
        chunk = self._stream.read(self._left + 1 if size < 0 else min(size, self._left + 1))
        self._left -= len(chunk)
        if self._left < 0:
            self._on_exceeded()
        return chunk

"""Globally unique, time-sortable record ids (ULID layout) and content hashes.

Every record the league ever shares gets one of each: the id says which record it is
and sorts by creation time; the content hash says what it holds, so the same id with
different content is detectable as a conflict.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import threading
import time
from typing import Any

_CROCKFORD = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"
ID_PATTERN = re.compile(r"[0-9A-HJKMNP-TV-Z]{26}")
_lock = threading.Lock()
_last = [0, 0]  # (milliseconds, random part) of the previous id


def new_id(now_ms: int | None = None) -> str:
    """A 26-character ULID: 48 bits of milliseconds then 80 random bits.

    Ids made by this process increase monotonically, even within one millisecond, so
    sorting by id keeps creation order in a tight loop. An explicit `now_ms` (for tests
    and imports of dated records) skips that bookkeeping.
    """
    if now_ms is not None:
        return _encode(now_ms, _random80())
    with _lock:
        ms = int(time.time() * 1000)
        last_ms, last_random = _last
        if ms <= last_ms:
            ms, random_part = last_ms, last_random + 1
        else:
            random_part = _random80() >> 1  # leave room to increment
        _last[:] = [ms, random_part]
    return _encode(ms, random_part)


def _random80() -> int:
    return int.from_bytes(os.urandom(10), "big")


def _encode(ms: int, random_part: int) -> str:
    value = ((ms & ((1 << 48) - 1)) << 80) | (random_part & ((1 << 80) - 1))
    return "".join(_CROCKFORD[(value >> shift) & 31] for shift in range(125, -1, -5))


def is_valid_id(text: object) -> bool:
    """Whether `text` is a well-formed id (safe to use in a file name)."""
    return isinstance(text, str) and ID_PATTERN.fullmatch(text) is not None


def id_time_ms(record_id: str) -> int:
    value = 0
    for char in record_id[:10]:
        value = value * 32 + _CROCKFORD.index(char)
    return value


def canonical_json(data: Any) -> bytes:
    """The bytes a content hash is taken over: sorted keys, no whitespace, UTF-8."""
    return json.dumps(
        data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
    ).encode("utf-8")


def content_hash(data: Any) -> str:
    """SHA-256 of the canonical JSON of `data`, as hex."""
    return hashlib.sha256(canonical_json(data)).hexdigest()

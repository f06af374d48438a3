"""Pull cursors: opaque strings the league saves between pulls.

A cursor is versioned JSON, zlib-compressed and base64-encoded, so it fits in one text
column and a cursor from another store type or a newer racer-tui is refused clearly.
"""

from __future__ import annotations

import base64
import binascii
import json
import zlib
from typing import Any

from league.sync.errors import CursorInvalidError

_MAX_CURSOR_BYTES = 64 * 1024 * 1024  # a runaway cursor is a bug, not a league


def pack_cursor(store_type: str, state: dict[str, Any]) -> str:
    payload = json.dumps({"store": store_type, "v": 1, **state}, separators=(",", ":"))
    return base64.urlsafe_b64encode(zlib.compress(payload.encode("utf-8"), 6)).decode("ascii")


def unpack_cursor(store_type: str, cursor: str) -> dict[str, Any]:
    """The state saved in `cursor`; CursorInvalidError if it is not one of this store type's."""
    try:
        decompressor = zlib.decompressobj()
        raw = decompressor.decompress(base64.urlsafe_b64decode(cursor), _MAX_CURSOR_BYTES)
        data = json.loads(raw)
    except (binascii.Error, zlib.error, ValueError, TypeError):
        data = None
    if not isinstance(data, dict) or data.get("store") != store_type or data.get("v") != 1:
        raise CursorInvalidError(
            f"the saved sync position is not a {store_type} store position: "
            "pull from the start to rebuild it"
        )
    return data

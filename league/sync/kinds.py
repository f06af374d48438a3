"""Which shared league table each record kind is, and the order they are inserted in.

Every table in league.records.SHARED_TABLES has exactly one kind, so a record's kind
says where it goes and nothing is folded into another record's body. Three kinds belong
to sync itself rather than to a league table: `racer_profile` (a racer's versioned
display name, see profiles.py), `bundle` (which S3 bundle holds which model) and `model`
(a racer's word that a model hash is theirs, see models.py).
"""

from __future__ import annotations

import hashlib
from typing import Final

from league.records import SHARED_TABLES

TABLE_OF_KIND: Final[dict[str, str]] = {
    "roster": "roster",
    "racer": "racers",
    "track": "tracks",
    "season": "seasons",
    "night": "nights",
    "entrant": "night_entrants",
    "heat": "heats",
    "night_closure": "night_closures",
    "night_change": "night_changes",
    "bracket": "brackets",
    "head_to_head": "head_to_heads",
    "submission": "submissions",
    "race": "races",
    "correction": "corrections",
}
KIND_OF_TABLE: Final[dict[str, str]] = {table: kind for kind, table in TABLE_OF_KIND.items()}
PROFILE_KIND: Final = "racer_profile"
BUNDLE_KIND: Final = "bundle"
MODEL_KIND: Final = "model"

# Parents before the records that refer to them: the order to insert a pulled page in. A
# model record goes before the results that race its model, so they need not wait for it.
LEAGUE_KINDS: Final[tuple[str, ...]] = tuple(KIND_OF_TABLE[table] for table in SHARED_TABLES)
_BEFORE_RESULTS: Final = LEAGUE_KINDS.index("submission")
INSERT_ORDER: Final[dict[str, int]] = {
    kind: position
    for position, kind in enumerate(
        (
            *LEAGUE_KINDS[:_BEFORE_RESULTS],
            MODEL_KIND,
            *LEAGUE_KINDS[_BEFORE_RESULTS:],
            PROFILE_KIND,
            BUNDLE_KIND,
        )
    )
}

_CROCKFORD: Final = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"


def profile_id(racer_name: str) -> str:
    """The id of a racer's profile record, derived from the racer's name.

    Racers are keyed by name (case-insensitively), and two machines may each have made
    a racer row for the same person before they synced; deriving the profile's id from
    the name gives every machine the same profile, so every edit of one racer's display
    name meets every other at the store's version check.
    """
    digest = hashlib.sha256(b"racer-tui racer profile\0" + racer_name.casefold().encode("utf-8"))
    value = int.from_bytes(digest.digest()[:16], "big") >> 2  # 126 bits: 26 characters
    return "".join(_CROCKFORD[(value >> shift) & 31] for shift in range(125, -1, -5))

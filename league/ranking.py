"""The one ranking function: every leaderboard, standings table and race report orders
results with `rank`, so every racer computes the same order from the same records.

The order is total, so a tie never depends on row order: the ranking score (lower is
better; no score ranks last), then fewer off-tracks in the scoring lap(s), then more valid
laps, then the earlier result, then the racer's name, and finally the record id.

"The earlier result" is the time a result claims (`recorded_at`), which a pull keeps from
being forged: dated no earlier than the league's founding, agreeing with its id, and for a
result that arrives more than a few minutes after its date and would win a tie by it, the
time this league first saw it (league.sync.dates; the cache's recorded_at is that time).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Protocol, TypeVar

from sim.race.rules import Verification


class Rankable(Protocol):
    """What ranking needs from a result; race results and submissions both provide it."""

    @property
    def score(self) -> float | None: ...
    @property
    def scoring_offtracks(self) -> int: ...
    @property
    def valid_laps(self) -> int: ...
    @property
    def recorded_at(self) -> str: ...  # ISO-8601 UTC or a time-sortable id: sorts by time
    @property
    def racer(self) -> str: ...
    @property
    def record_id(self) -> str: ...


RankedT = TypeVar("RankedT", bound=Rankable)


def ranking_key(entry: Rankable) -> tuple[int, float, int, int, str, str, str]:
    """Sort key for `entry`; exposed so SQL-side pre-filtering can mirror it in tests."""
    score = entry.score
    has_score = score is not None and math.isfinite(score)
    # Scores are lap times in seconds; rounding to the millisecond keeps float noise from
    # deciding a race that the timing screen shows as a tie.
    value = round(score, 3) if has_score and score is not None else math.inf
    return (
        0 if has_score else 1,
        value,
        entry.scoring_offtracks,
        -entry.valid_laps,
        entry.recorded_at,
        entry.racer.casefold(),
        entry.record_id,
    )


def rank(entries: Iterable[RankedT]) -> list[RankedT]:
    """Entries best first, in the league's total order."""
    return sorted(entries, key=ranking_key)


# Which standings (league.trust.standing) each verification rule ranks.
_COUNTED: dict[Verification, frozenset[str]] = {
    Verification.ANY: frozenset({"replayed", "verifiable", "unverifiable"}),
    Verification.VERIFIABLE: frozenset({"replayed", "verifiable"}),
    Verification.REPLAYED: frozenset({"replayed"}),
}


def counts_under(standing: str, required: Verification) -> bool:
    """Whether a result of this standing is ranked under rules requiring `required`; a board
    leaves the others out before it picks each racer's best (a racer's lesser verified
    result still counts when their best cannot)."""
    return standing in _COUNTED[required]

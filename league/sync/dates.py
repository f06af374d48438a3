"""Dates and ids that agree: a record may not claim to be older (or newer) than it can be.

A record's id carries the time it was made (sim.foundation.ids: 48 bits of milliseconds), and its
body carries its own date (`created_at`, a submission's `submitted_at`, a race's
`started_at`, a model record's `registered_at`); both come from the maker's clock in the
same save. Ties on a board go to the earlier result, and the first model record seen for
a model hash makes it that racer's, so a forged early date would win both: a pulled record
must have

- an id dated between 2024 (before racer-tui shared anything) and now, give or take
  DATE_TOLERANCE_MS;
- its body's date within DATE_TOLERANCE_MS of its id's, except a race, whose id is made
  when its result is saved: any time after it started (a race may be saved long after,
  a result file imported later, say), never before;
- when a racer (not an organiser) signed it, neither its id nor its date before the
  league's founding (the founding act's league id is made when the organiser founds it),
  so a result cannot rank first in a tie by a date older than the league. Racers and tracks
  may be older: they are names, made on a racer's laptop before they joined, and keep the
  rule of identity kinds (the first made wins; check_dates keeps them after 2024); so may
  a racer's proposal of their key, and their model records.

`check_dates` needs nothing but the record (validate.py calls it for every kind);
`founding_refusal` needs the roster (incoming.py calls it once the signer is known).
"""

from __future__ import annotations

import json
import time
from datetime import UTC, datetime
from typing import Final

from league.entries import refresh_entries
from league.store import League, now_iso
from league.sync.errors import RecordInvalidError
from league.sync.kinds import BUNDLE_KIND, MODEL_KIND, PROFILE_KIND
from league.sync.record import SyncRecord
from league.trust.roster import FOUNDER_ID, ROSTER_KIND, Roster
from sim.foundation.ids import id_time_ms
from sim.race.rules import RankingMethod

# How far apart two clocks, or two stamps of one save, may honestly be. A record's id and
# its date are taken by one clock a few milliseconds apart; the maker's clock and this
# machine's (a record "from the future") and the founder's (a record "before the league")
# differ by what laptops without a time server drift: seconds, rarely minutes. Ten minutes
# lets every honest record through and leaves a forger nothing worth having (a tie between
# a result here and one arriving later goes to the first seen whatever; see Arrivals).
DATE_TOLERANCE_MS: Final = 10 * 60 * 1000
EARLIEST_ID_MS: Final = int(datetime(2024, 1, 1, tzinfo=UTC).timestamp() * 1000)

# The body's date of each kind; kinds not here carry none (a profile's id is derived from
# its racer's name, a bundle record only maps two hashes).
DATE_FIELD: Final[dict[str, str]] = {
    "roster": "created_at",
    "racer": "created_at",
    "track": "created_at",
    "season": "created_at",
    "night": "created_at",
    "entrant": "created_at",
    "heat": "created_at",
    "night_closure": "created_at",
    "night_change": "created_at",
    "bracket": "created_at",
    "correction": "created_at",
    "submission": "submitted_at",
    "race": "started_at",
    "head_to_head": "started_at",
    MODEL_KIND: "registered_at",
}
# Names rather than results, made on a racer's laptop before they joined the league; a
# racer's proposal of their key (it grants nothing, and a laptop that was in another league
# proposed its key then: refused, its racer could never be admitted here); and a model
# record, made at a racer's first push, before their machine knows when the league began,
# and dated by their first result with the model (whose model is whose goes by which
# record was seen first, never by its date).
_OLDER_THAN_THE_LEAGUE: Final = frozenset(
    {"racer", "track", PROFILE_KIND, BUNDLE_KIND, ROSTER_KIND, MODEL_KIND}
)
IDENTITY_KINDS: Final = frozenset({"racer", "track", "season"})


def iso_ms(text: str) -> int:
    """Milliseconds since 1970 of an ISO-8601 time with a UTC offset (validate.py checked it)."""
    return int(datetime.fromisoformat(text).timestamp() * 1000)


def day_of(ms: int) -> str:
    try:
        return datetime.fromtimestamp(ms / 1000, UTC).strftime("%Y-%m-%d %H:%M UTC")
    except (OverflowError, OSError, ValueError):
        return "a time that does not exist"


def _id_time(record: SyncRecord) -> int | None:
    """When the record's id says it was made; None for ids that carry no time."""
    if record.kind == PROFILE_KIND:
        return None
    if record.kind == ROSTER_KIND and record.record_id == FOUNDER_ID:
        league = record.body.get("league")  # made when the organiser founded the league
        return id_time_ms(league) if isinstance(league, str) else None
    return id_time_ms(record.record_id)


def check_dates(record: SyncRecord, now_ms: int | None = None) -> None:
    """RecordInvalidError (one sentence) unless the record's id and dates agree and lie
    between 2024 and now (call after its fields were checked)."""
    made = _id_time(record)
    if made is None:
        return
    now = int(time.time() * 1000) if now_ms is None else now_ms
    if not EARLIEST_ID_MS <= made <= now + DATE_TOLERANCE_MS:
        why = (
            f"the first {record.kind} made wins its name everywhere"
            if record.kind in IDENTITY_KINDS
            else "ties and models go to the first made"
        )
        raise RecordInvalidError(
            f"its id claims it was made on {day_of(made)[:10]}, which cannot be true; {why}, "
            "so a forged date is not believed"
        )
    field = DATE_FIELD.get(record.kind)
    if field is None:
        return
    dated = iso_ms(str(record.body[field]))
    earliest, latest = dated - DATE_TOLERANCE_MS, dated + DATE_TOLERANCE_MS
    if record.kind in ("race", "head_to_head"):
        latest = made  # saved when it ended: any time after it started
    if not earliest <= made <= latest:
        raise RecordInvalidError(
            f"its {field} ({day_of(dated)}) and the time its id was made ({day_of(made)}) "
            "disagree, so one of them was written by hand"
        )


def iso_text(ms: int) -> str:
    """`ms` as the league writes times (league.store.now_iso): they sort as text."""
    stamp = datetime.fromtimestamp(ms / 1000, UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")
    return stamp[:-3] + "Z"


def founded_ms(roster: Roster) -> int | None:
    """When this league was founded (its founding act's league id), None before it is known."""
    return None if roster.league is None else id_time_ms(roster.league)


def founding_refusal(record: SyncRecord, roster: Roster) -> str | None:
    """Why a pulled record cannot be the league's (dated before it was founded), or None.
    An organiser's own records may be older: their league ran before it was shared."""
    founded = founded_ms(roster)
    made = _id_time(record)
    if founded is None or made is None or record.kind in _OLDER_THAN_THE_LEAGUE:
        return None
    field = DATE_FIELD.get(record.kind)
    if field is not None:  # a race's date may be older than its id (validate.py checked it)
        made = min(made, iso_ms(str(record.body[field])))
    if record.seal is not None and record.seal.signer in roster.organisers:
        return None
    if made >= founded - DATE_TOLERANCE_MS:
        return None
    return (
        f"it is dated {day_of(made)}, before this league was founded ({day_of(founded)}); "
        "nothing made before a league existed counts in it"
    )


class Arrivals:
    """Ties go to the result the league saw first. A pulled result dated more than
    DATE_TOLERANCE_MS before it arrived, that would win a tie (the same score, off-tracks
    and valid laps on the same board) by that date against another racer's result this
    league held before the page it came in, ranks from the time it arrived instead
    (`sync_first_seen`, which the leaderboard cache reads): nobody wins a tie by writing
    an early date. Results synced within the tolerance of being made, and results that
    arrive together, rank by their dates, as on the machines they came from, so every
    machine shows the same board; a racer who syncs later than that loses such a tie."""

    def __init__(self) -> None:
        self._inserted: list[str] = []

    def note(self, record: SyncRecord) -> None:
        """Call when a pulled submission or race was just inserted."""
        self._inserted.append(record.record_id)

    def settle(self, league: League) -> None:
        """Call once the leaderboard cache holds this page's results."""
        arrived = set(self._inserted)
        moved: list[str] = []
        late = iso_text(int(time.time() * 1000) - DATE_TOLERANCE_MS)
        for entry_id in self._inserted:
            if _wins_tie_by_date(league, entry_id, arrived, late):
                league.conn.execute(
                    "INSERT OR IGNORE INTO sync_first_seen (entry_id, seen_at) VALUES (?, ?)",
                    (entry_id, now_iso()),
                )
                moved.append(entry_id)
        self._inserted.clear()
        if moved:
            refresh_entries(league.conn, moved)


# Another racer's row on the same board (league.entries: each racer's best per ranking
# method, track, race type and physics) with the same score, off-tracks and valid laps and
# a later date: the board's index finds it by its exact score.
_TIE_ON_BOARD: Final = " UNION ALL ".join(
    "SELECT 1 FROM entries e JOIN board o "
    f"ON o.method = '{method.value}' AND o.track_hash = e.track_hash "
    "AND o.race_type = e.race_type AND o.physics = e.physics AND o.unscored = 0 "
    f"AND o.score = e.score_{method.value} "
    f"AND o.scoring_offtracks = e.offtracks_{method.value} "
    "AND o.valid_laps = e.valid_laps AND o.recorded_at > e.recorded_at "
    "AND o.racer <> e.racer "
    "WHERE e.entry_id = ?1 AND e.recorded_at < ?2 "
    "AND o.entry_id NOT IN (SELECT value FROM json_each(?3))"
    for method in RankingMethod
)


def _wins_tie_by_date(league: League, entry_id: str, arrived: set[str], late: str) -> bool:
    """Whether `entry_id`, dated before `late`, ties another racer's best result held
    before (not in `arrived`) on its board under some ranking method, and would rank
    ahead of it by its earlier date."""
    row = league.query_one(
        f"SELECT 1 FROM ({_TIE_ON_BOARD}) LIMIT 1",
        (entry_id, late, json.dumps(sorted(arrived))),
    )
    return row is not None

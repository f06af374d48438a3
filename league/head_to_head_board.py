"""The head-to-head board as every front end shows it: `racer-tui leaderboard --race-type
head-to-head` and the League screen read its rows, columns and JSON from here.

A head-to-head race ranks no laps (league.head_to_heads): its board is each racer's wins
and losses car for car, the rival cars they finished ahead of and behind, the cars (models)
they raced, and how many of their starts were in races replayed here (of those a replay
could check: a physical car's are timed by hand). A board counts the
races its verification asks for (every one, or only those this machine could race again or
has), and a rank is a racer's place on the whole board: naming one racer keeps their rank.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

from league.head_to_heads import (
    RecordedHeadToHead,
    head_to_head_board,
    head_to_head_races,
    record_between,
)
from league.report import Column
from league.store import League
from league.trust.standing import ResultStanding, Standing, head_to_head_standings
from sim.race.rules import Verification

# The lap boards' choices that mean nothing on a head-to-head board, and why: the command
# line refuses them in these words, and the League screen's filters and keys give way
# with them.
NOT_FOR_HEAD_TO_HEAD = {
    "season": "head-to-head races are not on nights' seasons yet",
    "by": "a head-to-head board ranks by wins, not by laps",
    "sort": "a head-to-head board is ranked by wins",
    "reverse": "a head-to-head board is ranked by wins",
}
# The standings a board of each verification counts.
_COUNTED = {
    Verification.ANY: {Standing.REPLAYED, Standing.VERIFIABLE, Standing.UNVERIFIABLE},
    Verification.VERIFIABLE: {Standing.REPLAYED, Standing.VERIFIABLE},
    Verification.REPLAYED: {Standing.REPLAYED},
}


@dataclass(frozen=True)
class HeadToHeadRow:
    """One racer's line on the board."""

    rank: int
    racer: str
    cars: tuple[str, ...]  # the models they raced, most starts first
    starts: int
    wins: int
    losses: int
    beaten: int  # rival cars finished behind theirs
    beaten_by: int  # rival cars finished ahead of theirs
    replayed_starts: int  # starts in races raced again here with the same result
    hand_timed_starts: int = 0  # physical cars' starts, timed by hand: never replayed

    @property
    def replayable_starts(self) -> int:
        return self.starts - self.hand_timed_starts

    @property
    def replayed_cell(self) -> str:
        """ "2 of 3" (of the starts a replay could check), or "hand-timed" when none could."""
        if not self.replayable_starts:
            return "hand-timed"
        return f"{self.replayed_starts} of {self.replayable_starts}"


@dataclass(frozen=True)
class HeadToHeadBoard:
    races: list[RecordedHeadToHead]  # the races it counts, oldest first
    rows: list[HeadToHeadRow]
    standings: dict[str, ResultStanding]  # each counted race's, by its id


def read_head_to_head_board(
    league: League,
    *,
    track_hash: str | None = None,
    night_id: str | None = None,
    racer: str | None = None,
    verification: Verification = Verification.ANY,
    local_models: Collection[str] = (),
) -> HeadToHeadBoard:
    """The board of the recorded head-to-head races on one track or of one night (or all),
    counting the races `verification` asks for; `racer` (a stored name) keeps only their
    row. `local_models` are the garage's model hashes, as for the lap boards' standings."""
    races = head_to_head_races(league, track_hash=track_hash, night_id=night_id)
    standings = head_to_head_standings(league, [race.id for race in races], local_models)
    counted = _COUNTED[verification]
    races = [race for race in races if standings[race.id].standing in counted]
    replayed = [race for race in races if standings[race.id].standing is Standing.REPLAYED]
    rows = [
        HeadToHeadRow(
            rank=rank,
            racer=standing.racer,
            cars=_cars_of(races, standing.racer),
            starts=standing.starts,
            wins=standing.wins,
            losses=standing.losses,
            beaten=standing.beaten,
            beaten_by=standing.beaten_by,
            replayed_starts=_starts_in(replayed, standing.racer),
            hand_timed_starts=_starts_in(
                [race for race in races if race.hand_timed], standing.racer
            ),
        )
        for rank, standing in enumerate(head_to_head_board(races), start=1)
        if racer is None or standing.racer == racer
    ]
    return HeadToHeadBoard(races, rows, {race.id: standings[race.id] for race in races})


def _cars_of(races: Sequence[RecordedHeadToHead], racer: str) -> tuple[str, ...]:
    starts = Counter(
        place.model_name for race in races for place in race.places if place.racer == racer
    )
    return tuple(model for model, _ in starts.most_common())  # ties: the first raced first


def _starts_in(races: Sequence[RecordedHeadToHead], racer: str) -> int:
    return sum(1 for race in races for place in race.places if place.racer == racer)


def cars_cell(row: HeadToHeadRow) -> str:
    """ "reference", or "fast-v2 (+1)" for a racer who raced another model as well."""
    more = len(row.cars) - 1
    return row.cars[0] + (f" (+{more})" if more else "") if row.cars else "-"


# The table's columns, in every format; `racer-tui leaderboard` titles them so too.
HEAD_TO_HEAD_COLUMNS = (
    Column("rank", lambda row: str(row.rank), numeric=True),
    Column("racer", lambda row: row.racer),
    Column("car", cars_cell),
    Column("wins", lambda row: str(row.wins), numeric=True),
    Column("losses", lambda row: str(row.losses), numeric=True),
    Column("ahead of", lambda row: str(row.beaten), numeric=True),
    Column("behind", lambda row: str(row.beaten_by), numeric=True),
    Column("replayed", lambda row: row.replayed_cell, numeric=True),
)


def head_to_head_json(board: HeadToHeadBoard, track_name: str | None) -> dict[str, Any]:
    """The board as one JSON document (`--format json`, and the League screen's export)."""
    return {
        "board": "head-to-head",
        "track": track_name,
        "races": len(board.races),
        "rows": [
            {
                "rank": row.rank,
                "racer": row.racer,
                "cars": list(row.cars),
                "starts": row.starts,
                "wins": row.wins,
                "losses": row.losses,
                "rivals_beaten": row.beaten,
                "beaten_by": row.beaten_by,
                "replayed_starts": row.replayed_starts,
                "hand_timed_starts": row.hand_timed_starts,
            }
            for row in board.rows
        ],
    }


@dataclass(frozen=True)
class RivalRecord:
    rival: str
    wins: int  # races the racer's better car finished ahead of the rival's
    losses: int


def rival_records(board: HeadToHeadBoard, racer: str) -> list[RivalRecord]:
    """`racer`'s record against each rival they raced, in the board's order."""
    raced = {place.racer for race in races_of(board, racer) for place in race.places}
    return [
        RivalRecord(rival.racer, *record_between(board.races, racer, rival.racer))
        for rival in head_to_head_board(board.races)  # every racer's, whoever `rows` keeps
        if rival.racer in raced and rival.racer != racer
    ]


def races_of(board: HeadToHeadBoard, racer: str) -> list[RecordedHeadToHead]:
    """The counted races `racer` started in, oldest first."""
    return [race for race in board.races if any(p.racer == racer for p in race.places)]

"""Where a racer stands on a track's leaderboard, said in one sentence.

After a submission or a recorded race, the racer wants to know how it went: this reads
the track's leaderboard of the entry's race type (the one ranking, league.leaderboard) and
finds the racer's row, which is their best entry there (maybe an earlier one than the
entry just added).
"""

from __future__ import annotations

from dataclasses import dataclass

from league.leaderboard import Filters, board_of, leaderboard
from league.race_types import TIME_TRIAL
from league.racers import find_racer
from league.store import League
from sim.race.rules import RankingMethod


@dataclass(frozen=True)
class BoardPlace:
    """The racer's row on one track's leaderboard."""

    rank: int  # 1 = leading
    entries: int  # racers on that board
    track_name: str
    display_name: str
    entry_id: str  # the racer's entry that counts there (their best)
    best_lap: float | None


def ordinal(number: int) -> str:
    """1st, 2nd, 3rd, 4th, 11th, 12th, 13th, 21st..."""
    if 10 <= number % 100 <= 20:
        suffix = "th"
    else:
        suffix = {1: "st", 2: "nd", 3: "rd"}.get(number % 10, "th")
    return f"{number}{suffix}"


def board_place(
    league: League,
    racer: str,
    track_hash: str,
    method: RankingMethod = RankingMethod.BEST_LAP,
    race_type: str = TIME_TRIAL,
) -> BoardPlace | None:
    """`racer`'s place on the track's leaderboard of `race_type` (ranked by `method`), or
    None when they have no entry on it."""
    found = find_racer(league, racer)
    if found is None:
        return None
    rows = leaderboard(league, Filters(track_hash=track_hash, race_type=race_type), method)
    for row in rows:
        if row.racer == found.name:
            return BoardPlace(
                rank=row.rank,
                entries=sum(1 for other in rows if board_of(other) == board_of(row)),
                track_name=row.track_name,
                display_name=row.display_name,
                entry_id=row.record_id,
                best_lap=row.best_lap,
            )
    return None


def place_sentence(place: BoardPlace | None, entry_id: str) -> str:
    """How the entry `entry_id` went, for a notification."""
    if place is None:
        return "It is in the league, but not on that track's leaderboard."
    where = (
        f"{place.display_name} is {ordinal(place.rank)} of {place.entries} on "
        f"{place.track_name}'s leaderboard"
    )
    if place.entry_id != entry_id:
        return f"{where} with an earlier entry, which this one does not beat."
    return f"{where}."

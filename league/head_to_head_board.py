"""The head-to-head board as the command line (`racer-tui leaderboard --race-type
head-to-head`) and the web pages show it, and its JSON, one format whichever is asked.

A head-to-head race ranks no laps (league.head_to_heads): its board is each racer's wins
and losses, car for car, the rival cars they finished ahead of and behind, and how many
of their starts were in races replayed on this machine (league.trust.standing). A board
can count only the races this machine can vouch for (`verification`).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from typing import Any

from league.head_to_heads import HeadToHeadStanding, head_to_head_board, head_to_head_races
from league.store import League
from league.tracks import LeagueTrack
from league.trust.standing import Standing, head_to_head_standings
from sim.race.rules import Verification

# The standings of the races a board counts, by the verification it asks for.
_COUNTED = {
    Verification.ANY: {Standing.REPLAYED, Standing.VERIFIABLE, Standing.UNVERIFIABLE},
    Verification.VERIFIABLE: {Standing.REPLAYED, Standing.VERIFIABLE},
    Verification.REPLAYED: {Standing.REPLAYED},
}


@dataclass(frozen=True)
class HeadToHeadRow:
    rank: int
    standing: HeadToHeadStanding
    replayed_starts: int  # of its starts, those in races replayed here

    def to_json(self) -> dict[str, Any]:
        return {
            "rank": self.rank,
            "racer": self.standing.racer,
            "starts": self.standing.starts,
            "wins": self.standing.wins,
            "losses": self.standing.losses,
            "rivals_beaten": self.standing.beaten,
            "beaten_by": self.standing.beaten_by,
            "replayed_starts": self.replayed_starts,
        }


@dataclass(frozen=True)
class HeadToHeadBoard:
    track: str | None  # the track's name, for a board of one track
    races: int  # the races it counts
    rows: tuple[HeadToHeadRow, ...]  # ranked by wins

    def to_json(self) -> dict[str, Any]:
        return {
            "board": "head-to-head",
            "track": self.track,
            "races": self.races,
            "rows": [row.to_json() for row in self.rows],
        }


def league_head_to_head_board(
    league: League,
    local_models: Collection[str],
    *,
    track: LeagueTrack | None = None,
    night_id: str | None = None,
    verification: Verification = Verification.ANY,
    racer: str | None = None,
    limit: int | None = None,
) -> HeadToHeadBoard:
    """The board of the league's head-to-head races (on `track`, of one night), counting
    those `verification` asks for; `racer` (a racer's own name) keeps that racer's row,
    `limit` the first rows. `local_models`: the garage's model hashes."""
    races = head_to_head_races(
        league,
        track_hash=track.track_hash if track is not None else None,
        night_id=night_id,
    )
    standings = head_to_head_standings(league, [race.id for race in races], local_models)
    counted = _COUNTED[verification]
    races = [race for race in races if standings[race.id].standing in counted]
    replayed = {race.id for race in races if standings[race.id].standing is Standing.REPLAYED}
    board = head_to_head_board(races)
    if racer is not None:
        board = [row for row in board if row.racer == racer]
    if limit is not None:
        board = board[:limit]
    rows = tuple(
        HeadToHeadRow(
            rank,
            row,
            sum(
                1
                for race in races
                if race.id in replayed
                for place in race.places
                if place.racer == row.racer
            ),
        )
        for rank, row in enumerate(board, start=1)
    )
    return HeadToHeadBoard(track.name if track is not None else None, len(races), rows)

"""`racer-tui leaderboard --race-type head-to-head`: who beat whom in the league's recorded
head-to-head races (league.head_to_heads), as a table or JSON.

A head-to-head race ranks no laps: its board is each racer's wins and losses, car for car,
the rival cars they finished ahead of and behind, and how many of their starts were in
races verified by replay on this machine; `--verification` counts only the races
replayed here (or also those every car of which could be).
"""

from __future__ import annotations

import argparse
from typing import Any

from rich.text import Text

from league.errors import LeagueError
from league.head_to_heads import HeadToHeadStanding, head_to_head_board, head_to_head_races
from league.nights import get_night
from league.racers import get_racer
from league.store import League
from league.tracks import track_for
from league.trust.standing import Standing, head_to_head_standings
from racer_tui.cli.output import plain_table, print_json, print_table
from sim.race.rules import Verification

# The lap boards' options a head-to-head board has no use for, and why.
_NOT_FOR_HEAD_TO_HEAD = (
    ("season", "--season: head-to-head races are not on nights' seasons yet"),
    ("by", "--by: a head-to-head board ranks by wins, not by laps"),
    ("reverse", "--reverse: a head-to-head board is ranked by wins"),
)
_COUNTED = {
    Verification.ANY: {Standing.REPLAYED, Standing.VERIFIABLE, Standing.UNVERIFIABLE},
    Verification.VERIFIABLE: {Standing.REPLAYED, Standing.VERIFIABLE},
    Verification.REPLAYED: {Standing.REPLAYED},
}


def show_head_to_head_board(
    league: League, args: argparse.Namespace, models_here: frozenset[str]
) -> int:
    """The board, filtered as the options say (--track, --night, --racer,
    --verification), as a table or JSON."""
    for option, why in _NOT_FOR_HEAD_TO_HEAD:
        if getattr(args, option, None):
            raise LeagueError(f"{why}; leave it out.")
    if args.sort != "rank":
        raise LeagueError("--sort: a head-to-head board is ranked by wins; leave it out.")
    if args.format not in ("table", "json"):
        raise LeagueError(
            f"--format {args.format}: a head-to-head board is a table or JSON (--format json)."
        )
    track = track_for(league, args.track) if args.track else None
    night = get_night(league, args.night) if args.night else None
    races = head_to_head_races(
        league,
        track_hash=track.track_hash if track is not None else None,
        night_id=night.id if night is not None else None,
    )
    standings = head_to_head_standings(league, [race.id for race in races], models_here)
    counted = _COUNTED[Verification(args.verification)]
    races = [race for race in races if standings[race.id].standing in counted]
    replayed = {race.id for race in races if standings[race.id].standing is Standing.REPLAYED}
    board = head_to_head_board(races)
    if args.racer:
        racer = get_racer(league, args.racer).name
        board = [row for row in board if row.racer == racer]
    if args.limit is not None:
        if args.limit < 1:
            raise LeagueError("--limit must be at least 1.")
        board = board[: args.limit]
    replayed_starts = {
        row.racer: sum(
            1
            for race in races
            if race.id in replayed
            for place in race.places
            if place.racer == row.racer
        )
        for row in board
    }
    if args.format == "json":
        print_json(
            {
                "board": "head-to-head",
                "track": track.name if track is not None else None,
                "races": len(races),
                "rows": [
                    _row_json(rank, row, replayed_starts[row.racer])
                    for rank, row in enumerate(board, start=1)
                ],
            }
        )
        return 0
    where = f" on {track.name}" if track is not None else ""
    if not board:
        print(
            f"No head-to-head races{where} yet: race models together with racer-tui --race "
            "A B --rules head-to-head --record."
        )
        return 0
    table = plain_table(f"Head-to-head{where}: {len(races)} races, ranked by wins")
    # Starts are wins and losses, so not a column of their own; names get room first (a
    # name cut short could read as another racer), and on a narrow terminal the headers of
    # numbers wrap.
    longest = max(len(row.racer) for row in board)
    table.add_column("#", justify="right")
    table.add_column("racer", min_width=min(longest, 24), overflow="fold")
    for title in ("wins", "losses", "ahead of", "behind", "replayed"):
        table.add_column(title, justify="right")
    for rank, row in enumerate(board, start=1):
        table.add_row(
            str(rank),
            Text(row.racer),  # a name from another machine: never markup
            str(row.wins),
            str(row.losses),
            str(row.beaten),
            str(row.beaten_by),
            f"{replayed_starts[row.racer]} of {row.starts}",
        )
    print_table(table)
    return 0


def _row_json(rank: int, row: HeadToHeadStanding, replayed: int) -> dict[str, Any]:
    return {
        "rank": rank,
        "racer": row.racer,
        "starts": row.starts,
        "wins": row.wins,
        "losses": row.losses,
        "rivals_beaten": row.beaten,
        "beaten_by": row.beaten_by,
        "replayed_starts": replayed,
    }

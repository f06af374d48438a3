"""`racer-tui leaderboard --race-type head-to-head`: who beat whom in the league's recorded
head-to-head races, as a table or JSON (league.head_to_head_board, which the web pages
show too).

A head-to-head race ranks no laps: its board is each racer's wins and losses, car for car,
the rival cars they finished ahead of and behind, and how many of their starts were in
races verified by replay on this machine; `--verification` counts only the races
replayed here (or also those every car of which could be).
"""

from __future__ import annotations

import argparse

from rich.text import Text

from league.errors import LeagueError
from league.head_to_head_board import league_head_to_head_board
from league.nights import get_night
from league.racers import get_racer
from league.store import League
from league.tracks import track_for
from racer_tui.cli.output import plain_table, print_json, print_table
from sim.race.rules import Verification

# The lap boards' options a head-to-head board has no use for, and why.
_NOT_FOR_HEAD_TO_HEAD = (
    ("season", "--season: head-to-head races are not on nights' seasons yet"),
    ("by", "--by: a head-to-head board ranks by wins, not by laps"),
    ("reverse", "--reverse: a head-to-head board is ranked by wins"),
)


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
    if args.limit is not None and args.limit < 1:
        raise LeagueError("--limit must be at least 1.")
    track = track_for(league, args.track) if args.track else None
    board = league_head_to_head_board(
        league,
        models_here,
        track=track,
        night_id=get_night(league, args.night).id if args.night else None,
        verification=Verification(args.verification),
        racer=get_racer(league, args.racer).name if args.racer else None,
        limit=args.limit,
    )
    if args.format == "json":
        print_json(board.to_json())
        return 0
    where = f" on {track.name}" if track is not None else ""
    if not board.rows:
        print(
            f"No head-to-head races{where} yet: race models together with racer-tui --race "
            "A B --rules head-to-head --record."
        )
        return 0
    table = plain_table(f"Head-to-head{where}: {board.races} races, ranked by wins")
    # Starts are wins and losses, so not a column of their own; names get room first (a
    # name cut short could read as another racer), and on a narrow terminal the headers of
    # numbers wrap.
    longest = max(len(row.standing.racer) for row in board.rows)
    table.add_column("#", justify="right")
    table.add_column("racer", min_width=min(longest, 24), overflow="fold")
    for title in ("wins", "losses", "ahead of", "behind", "replayed"):
        table.add_column(title, justify="right")
    for row in board.rows:
        table.add_row(
            str(row.rank),
            Text(row.standing.racer),  # a name from another machine: never markup
            str(row.standing.wins),
            str(row.standing.losses),
            str(row.standing.beaten),
            str(row.standing.beaten_by),
            f"{row.replayed_starts} of {row.standing.starts}",
        )
    print_table(table)
    return 0

"""`racer-tui leaderboard --race-type head-to-head`: who beat whom in the league's recorded
head-to-head races, as a table or JSON: the board's rows and columns are
league.head_to_head_board's, which the League screen shows too.

A head-to-head race ranks no laps: its board is each racer's wins and losses, car for car,
the rival cars they finished ahead of and behind, and how many of their starts were in
races verified by replay on this machine; `--verification` counts only the races
replayed here (or also those every car of which could be).
"""

from __future__ import annotations

import argparse

from rich.text import Text

from league.errors import LeagueError
from league.head_to_head_board import (
    HEAD_TO_HEAD_COLUMNS,
    NOT_FOR_HEAD_TO_HEAD,
    head_to_head_json,
    read_head_to_head_board,
)
from league.nights import get_night
from league.racers import get_racer
from league.store import League
from league.tracks import track_for
from racer_tui.cli.output import plain_table, print_json, print_table
from sim.race.rules import Verification


def show_head_to_head_board(
    league: League, args: argparse.Namespace, models_here: frozenset[str]
) -> int:
    """The board, filtered as the options say (--track, --night, --racer,
    --verification), as a table or JSON."""
    for option, why in NOT_FOR_HEAD_TO_HEAD.items():
        given = args.sort != "rank" if option == "sort" else getattr(args, option, None)
        if given:
            raise LeagueError(f"--{option}: {why}; leave it out.")
    if args.format not in ("table", "json"):
        raise LeagueError(
            f"--format {args.format}: a head-to-head board is a table or JSON (--format json)."
        )
    if args.limit is not None and args.limit < 1:
        raise LeagueError("--limit must be at least 1.")
    track = track_for(league, args.track) if args.track else None
    night = get_night(league, args.night) if args.night else None
    board = read_head_to_head_board(
        league,
        track_hash=track.track_hash if track is not None else None,
        night_id=night.id if night is not None else None,
        racer=get_racer(league, args.racer).name if args.racer else None,
        verification=Verification(args.verification),
        local_models=models_here,
    )
    rows = board.rows[: args.limit]
    if args.format == "json":
        document = head_to_head_json(board, track.name if track is not None else None)
        print_json({**document, "rows": document["rows"][: args.limit]})
        return 0
    where = f" on {track.name}" if track is not None else ""
    if not rows:
        print(
            f"No head-to-head races{where} yet: race models together with racer-tui --race "
            "A B --rules head-to-head --record."
        )
        return 0
    table = plain_table(f"Head-to-head{where}: {len(board.races)} races, ranked by wins")
    # Names get room first (a name cut short could read as another racer), so the cars
    # are left to --format json at 80 columns; on a narrow terminal the headers of numbers
    # wrap.
    columns = [column for column in HEAD_TO_HEAD_COLUMNS if column.title != "car"]
    longest = max(len(row.racer) for row in rows)
    for column in columns:
        if column.title == "racer":
            table.add_column("racer", min_width=min(longest, 24), overflow="fold")
        else:
            table.add_column(column.title, justify="right" if column.numeric else "left")
    for row in rows:
        # A name from another machine: never markup.
        table.add_row(*(Text(column.cell(row)) for column in columns))
    print_table(table)
    return 0

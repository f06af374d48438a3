"""`racer-tui season ...`, `racer-tui racer ...` and `racer-tui correct ...`: the league's
seasons, its racers (and their keys) and the corrections made to its results."""

from __future__ import annotations

import argparse

from rich.text import Text

from league import racers, seasons
from league.corrections import disqualify_lap, list_corrections, rename_racer
from league.opening import open_league
from league.racers import HEX_COLOUR
from league.store import League
from racer_tui.cli.league_commands import key_parsers, keys
from racer_tui.cli.output import plain_table, print_json, print_table
from sim.foundation.plural import counted


def run(args: argparse.Namespace) -> int:
    with open_league(args.db) as league:
        if args.command == "season":
            return season_command(league, args)
        if args.command == "racer":
            return racer_command(league, args)
        return correct_command(league, args)


def season_command(league: League, args: argparse.Namespace) -> int:

    action = args.season_command
    if action == "new":
        points = seasons.parse_points(args.points) if args.points else seasons.DEFAULT_POINTS
        season = seasons.new_season(league, args.name, points)
        points_text = "-".join(str(p) for p in season.points)
        print(f"Started season {season.name} ({season.id}); points {points_text}.")
        return 0
    if action == "list":
        found = seasons.list_seasons(league)
        if args.json:
            print_json([{"id": f.id, "name": f.name, "points": list(f.points)} for f in found])
            return 0
        table = plain_table("Seasons")
        for title in ("id", "name", "points"):
            table.add_column(title)
        for found_season in found:
            table.add_row(
                found_season.id,
                Text(found_season.name),
                "-".join(str(p) for p in found_season.points),
            )
        print_table(table)
        return 0
    season = seasons.get_season(league, args.season)
    if args.json:
        print_json(seasons.season_json(league, season))
        return 0
    standings = seasons.season_standings(league, season)
    nights_closed = len(seasons.closed_nights(league, season))
    table = plain_table(f"Season {season.name}: {counted(nights_closed, 'closed night')}")
    for title, right in (
        ("pos", True),
        ("racer", False),
        ("points", True),
        ("nights", True),
        ("wins", True),
    ):
        table.add_column(title, justify="right" if right else "left")
    for s in standings:
        table.add_row(
            str(s.position), Text(s.display_name), str(s.points), str(s.nights), str(s.wins)
        )
    print_table(table)
    return 0


def racer_command(league: League, args: argparse.Namespace) -> int:

    action = args.racer_command
    if action in key_parsers.ACTIONS:
        return keys.run(league, args)
    if action == "add":
        racer = racers.add_racer(
            league, args.name, display_name=args.display_name, colour=args.colour
        )
        print(f"Added racer {racer.name}.")
        return 0
    if action == "rename":
        rename_racer(league, args.name, args.new_display_name, by=args.by, reason=args.reason)
        print(f"{args.name} is now shown as {args.new_display_name.strip()}.")
        return 0
    found = racers.list_racers(league)
    if args.json:
        print_json(
            [
                {"name": r.name, "display_name": r.display_name, "colour": r.colour, "id": r.id}
                for r in found
            ]
        )
        return 0
    table = plain_table("Racers")
    for title in ("name", "shown as", "colour"):
        table.add_column(title)
    for r in found:
        # Colours may come from other racers' machines: only a checked #rrggbb is a style.
        style = r.colour if HEX_COLOUR.fullmatch(r.colour) else ""
        table.add_row(Text(r.name), Text(r.display_name), Text(r.colour, style=style))
    print_table(table)
    return 0


def correct_command(league: League, args: argparse.Namespace) -> int:

    if args.correct_command == "lap":
        correction = disqualify_lap(
            league, args.entry_id, args.lap_number, reason=args.reason, by=args.by
        )
        print(f"Lap {args.lap_number} of {args.entry_id.upper()} disqualified ({correction}).")
        return 0
    found = list_corrections(league, args.target)
    if args.json:
        print_json([c.__dict__ for c in found])
        return 0
    table = plain_table("Corrections")
    for title in ("id", "what", "target", "by", "why", "when"):
        table.add_column(title)
    for c in found:
        what = (
            f"lap {c.lap_number} disqualified"
            if c.kind == "disqualify_lap"
            else (f"shown as {c.new_value}")
        )
        table.add_row(
            c.id, Text(what), Text(c.target), Text(c.made_by), Text(c.reason), c.created_at[:16]
        )
    print_table(table)
    return 0

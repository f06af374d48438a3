"""A league command run: its league opened, then its handler."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from league.opening import open_league
from league.store import League
from racer_tui.cli.app_launch import AppLaunch
from racer_tui.cli.league_commands import board, nights, people

HANDLERS: dict[str, Callable[[League, argparse.Namespace], int]] = {
    "submit": board.submit,
    "leaderboard": board.show_leaderboard,
    "night": nights.night_command,
    "season": people.season_command,
    "racer": people.racer_command,
    "correct": people.correct_command,
}


def run(args: argparse.Namespace) -> int | AppLaunch:
    if args.command == "night" and args.night_command == "projector":
        return nights.projector(args)
    with open_league(args.db) as league:
        return HANDLERS[args.command](league, args)

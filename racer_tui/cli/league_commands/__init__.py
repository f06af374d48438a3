"""`racer-tui submit | leaderboard | night | season | racer | correct`: the league, headless.

Every command takes `--db FILE` (default: league.db in the data directory). Racer names
and other user text go into rich tables as `Text` cells, never as markup.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path
from typing import TYPE_CHECKING

from league.race_types import HEAD_TO_HEAD_BOARD, OPTION_CHOICES, option_name
from racer_tui.cli.app_launch import AppLaunch
from racer_tui.cli.league_commands import key_parsers
from racer_tui.cli.rules_option import HELP as RULES_HELP
from sim.race.rules import HEAD_TO_HEAD_RULES, RULE_PRESETS, Verification
from sim.tracks.catalog import DEFAULT_TRACK

if TYPE_CHECKING:
    Parsers = argparse._SubParsersAction[argparse.ArgumentParser]

NAMES = ("submit", "leaderboard", "night", "season", "racer", "correct")
FORMATS = ("table", "json", "csv", "markdown")
# The leaderboard's formats: the above, and DeepRacer on AWS's rankings (league.droa_rankings).
BOARD_FORMATS = (*FORMATS, "droa")


def _db_option() -> argparse.ArgumentParser:
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument(
        "--db",
        type=Path,
        metavar="FILE",
        help="league database (default: league.db in the data dir)",
    )
    return parent


def register(commands: Parsers) -> None:
    db = _db_option()
    _register_submit(commands, db)
    _register_leaderboard(commands, db)
    _register_night(commands, db)
    _register_season(commands, db)
    _register_racer(commands, db)
    _register_correct(commands, db)


def _register_submit(commands: Parsers, db: argparse.ArgumentParser) -> None:
    submit = commands.add_parser(
        "submit",
        parents=[db],
        help="submit a model's evaluation to the league",
        description="Assemble a submission from a garage model, a racer-tui model folder, a "
        "DeepRacer-for-Cloud model folder or an AWS console log download.",
    )
    submit.add_argument("model", help="garage model name, or a folder path")
    submit.add_argument("--racer", required=True, help="who is submitting (plain text)")
    submit.add_argument(
        "--track", help="track name or .npy file (needed when the files do not say)"
    )
    submit.add_argument("--evaluation", type=Path, metavar="FILE", help="evaluation metrics file")
    submit.add_argument("--model-name", help="name to list the model under (default: the folder)")
    submit.add_argument(
        "--stale-ok",
        action="store_true",
        help="submit an evaluation made before the model last trained",
    )
    submit.add_argument("--json", action="store_true")


def _register_leaderboard(commands: Parsers, db: argparse.ArgumentParser) -> None:
    board = commands.add_parser(
        "leaderboard", parents=[db], help="each racer's best entry per track, ranked"
    )
    board.add_argument("--track", help="only this track")
    board.add_argument(
        "--race-type",
        type=lambda text: option_name(text.strip().lower()),
        choices=(*OPTION_CHOICES, HEAD_TO_HEAD_BOARD),
        help="which of a track's boards: time-trial (the default with --track), "
        "object-avoidance or head-to-bot; without --track, every race type's boards; "
        "head-to-head: wins and losses in recorded head-to-head races",
    )
    board.add_argument("--racer", help="only this racer")
    board.add_argument("--night", help="only races of this league night")
    board.add_argument("--season", help="only races of this season's nights")
    board.add_argument(
        "--by",
        choices=("best", "average", "total"),
        help="rank by best lap (default), "
        "best average of 3 consecutive laps, or total time of 3 laps",
    )
    board.add_argument(
        "--sort",
        default="rank",
        metavar="COLUMN",
        help="rank, racer, model, track, score, best, average, laps, offtracks, submitted",
    )
    board.add_argument(
        "--verification",
        choices=[level.value for level in Verification],
        default=Verification.ANY.value,
        help="rank only results verified by replay on this machine (replayed), or those too "
        "whose model is here to replay (verifiable); every row says which it is",
    )
    board.add_argument("--reverse", action="store_true", help="reverse the sort order")
    board.add_argument("--limit", type=int, metavar="N", help="show the first N rows")
    board.add_argument(
        "--format",
        choices=BOARD_FORMATS,
        default="table",
        help="droa: the rankings as DeepRacer on AWS writes them (JSON, whole milliseconds)",
    )


def _register_night(commands: Parsers, db: argparse.ArgumentParser) -> None:
    night = commands.add_parser("night", help="league nights: entrants, heats, standings")
    actions = night.add_subparsers(dest="night_command", metavar="ACTION", required=True)
    new = actions.add_parser("new", parents=[db], help="open a night; its rules are frozen")
    new.add_argument(
        "--track",
        default=DEFAULT_TRACK,
        help=f"the night's track (default: {DEFAULT_TRACK}, re:Invent 2018)",
    )
    rules = new.add_mutually_exclusive_group()
    rules.add_argument(
        "--rules",
        metavar="FILE|PRESET",
        help=f"{RULES_HELP} (default: the league rules)",
    )
    rules.add_argument(
        "--preset",
        choices=[name for name, _, _ in RULE_PRESETS],
        help="; ".join(f"{name}: {what}" for name, what, _ in RULE_PRESETS),
    )
    new.add_argument(
        "--laps",
        type=int,
        metavar="N",
        help="a lap-count race: each heat ends after N laps, or when the window closes first",
    )
    new.add_argument(
        "--verification",
        choices=[level.value for level in Verification],
        help="which heats the standings count: any (the default), verifiable (the host can "
        "race them again) or replayed (the host raced them again at `night close`, with the "
        "same laps); frozen with the rules",
    )
    new.add_argument("--name")
    new.add_argument("--date", metavar="YYYY-MM-DD", help="the day it is held (default: today)")
    new.add_argument("--season", help="season name or id the night counts for")
    listing = actions.add_parser("list", parents=[db], help="all nights")
    listing.add_argument("--json", action="store_true")
    add = actions.add_parser("add", parents=[db], help="enter a racer with a model")
    add.add_argument("night", help="night id or name")
    add.add_argument("--racer", required=True)
    add.add_argument("--model", required=True, help="garage model name or .racer-bundle file")
    draw = actions.add_parser("draw", parents=[db], help="draw the heat order")
    draw.add_argument("night")
    draw.add_argument("--seed", type=int)
    run = actions.add_parser("run", parents=[db], help="run the waiting heats headless")
    run.add_argument("night")
    run.add_argument("--heats", type=int, metavar="N", help="run only the next N heats")
    show = actions.add_parser("show", parents=[db], help="rules, heats and standings")
    show.add_argument("night")
    show.add_argument("--json", action="store_true", help="the same as --format json")
    show.add_argument(
        "--format",
        choices=FORMATS,
        default="table",
        help="json: the whole night; csv, markdown: the standings with points",
    )
    close = actions.add_parser("close", parents=[db], help="close the night; print standings")
    close.add_argument("night")
    close.add_argument("--by", help="who closes it (default: this machine's racer name)")
    close.add_argument("--force", action="store_true", help="close even with heats waiting")
    close.add_argument("--json", action="store_true")
    projector = actions.add_parser(
        "projector", parents=[db], help="the night full-screen, for the venue's big screen"
    )
    projector.add_argument("night")
    withdraw = actions.add_parser(
        "withdraw", parents=[db], help="take an entrant out before their heat"
    )
    withdraw.add_argument("night")
    withdraw.add_argument("racer")
    withdraw.add_argument("--model", help="which car, when the racer entered more than one")
    withdraw.add_argument("--by", help="who withdraws them (default: this machine's racer name)")
    move = actions.add_parser("move", parents=[db], help="move a waiting heat in the order")
    move.add_argument("night")
    move.add_argument("racer")
    move.add_argument(
        "--to", type=int, required=True, metavar="N", help="its place among the heats to race"
    )
    move.add_argument("--model", help="which car, when the racer entered more than one")
    delete = actions.add_parser("delete", parents=[db], help="delete a night with no heat raced")
    delete.add_argument("night")
    delete.add_argument("--by", help="who deletes it (default: this machine's racer name)")
    bracket = actions.add_parser(
        "bracket", parents=[db], help="draw the knock-out bracket from the night's standings"
    )
    bracket.add_argument("night")
    bracket.add_argument(
        "--size",
        type=int,
        metavar="N",
        help="seed the best N qualifiers (default: every racer with a counting result)",
    )
    bracket.add_argument(
        "--double", action="store_true", help="double elimination: out after a second loss"
    )
    bracket.add_argument(
        "--physical",
        action="store_true",
        help="seed the physical cars: each match timed by hand on the real track, in the app",
    )
    bracket.add_argument(
        "--laps",
        type=int,
        default=HEAD_TO_HEAD_RULES.lap_count,
        metavar="N",
        help="laps of each match, the first car past the line wins "
        f"(default: {HEAD_TO_HEAD_RULES.lap_count}, as simapp's head-to-head)",
    )
    match = actions.add_parser("match", parents=[db], help="race the bracket's next matches")
    match.add_argument("night")
    match.add_argument("--matches", type=int, metavar="N", help="race only the next N matches")


def _register_season(commands: Parsers, db: argparse.ArgumentParser) -> None:
    season = commands.add_parser("season", help="seasons and their standings")
    actions = season.add_subparsers(dest="season_command", metavar="ACTION", required=True)
    new = actions.add_parser("new", parents=[db], help="start a season")
    new.add_argument("name")
    new.add_argument("--points", help="points per place, e.g. 25,18,15,12,10,8,6,4,2,1")
    show = actions.add_parser("show", parents=[db], help="season standings")
    show.add_argument("season", help="season name or id")
    show.add_argument("--json", action="store_true")
    listing = actions.add_parser("list", parents=[db], help="all seasons")
    listing.add_argument("--json", action="store_true")


def _register_racer(commands: Parsers, db: argparse.ArgumentParser) -> None:
    racer = commands.add_parser("racer", help="racers: add, list, rename; signing keys")
    actions = racer.add_subparsers(dest="racer_command", metavar="ACTION", required=True)
    add = actions.add_parser("add", parents=[db], help="add a racer")
    add.add_argument("name")
    add.add_argument("--display-name")
    add.add_argument("--colour", help="#rrggbb")
    listing = actions.add_parser("list", parents=[db], help="all racers")
    listing.add_argument("--json", action="store_true")
    rename = actions.add_parser("rename", parents=[db], help="change a racer's display name")
    rename.add_argument("name")
    rename.add_argument("new_display_name")
    rename.add_argument("--by", required=True, help="who makes the change")
    rename.add_argument("--reason", default="new display name")
    key_parsers.register(actions, db)


def _register_correct(commands: Parsers, db: argparse.ArgumentParser) -> None:
    correct = commands.add_parser("correct", help="corrections: disqualify a lap, list them")
    actions = correct.add_subparsers(dest="correct_command", metavar="ACTION", required=True)
    lap = actions.add_parser("lap", parents=[db], help="disqualify one lap")
    lap.add_argument("entry_id", metavar="RACE_ID", help="race or submission id")
    lap.add_argument("lap_number", type=int, metavar="LAP_NO")
    lap.add_argument("--reason", required=True)
    lap.add_argument("--by", required=True, help="who makes the correction")
    listing = actions.add_parser("list", parents=[db], help="all corrections")
    listing.add_argument("--target", help="only corrections of this race, submission or racer")
    listing.add_argument("--json", action="store_true")


# The module that runs each command (its `run(args)`), imported when the command runs, not
# for `--help` or the app's start: the league's modules load SQLite with sqlite-utils (and
# pandas) and the simulator.
HANDLER_MODULES = {
    "submit": "board",
    "leaderboard": "board",
    "night": "nights",
    "season": "people",
    "racer": "people",
    "correct": "people",
}


def run(args: argparse.Namespace) -> int | AppLaunch:
    handlers = importlib.import_module(f"{__name__}.{HANDLER_MODULES[args.command]}")
    result: int | AppLaunch = handlers.run(args)
    return result

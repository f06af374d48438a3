"""`racer-tui submit | leaderboard | night | season | racer | correct`: the league, headless.

Every command takes `--db FILE` (default: league.db in the data directory). Racer names
and other user text go into rich tables as `Text` cells, never as markup.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich import box
from rich.table import Table
from rich.text import Text

from league.errors import LeagueError
from league.race_types import OPTION_CHOICES, option_name
from racer_tui.cli import key_commands
from racer_tui.cli.app_launch import AppLaunch
from racer_tui.cli.output import print_json, print_table
from racer_tui.cli.rules_option import HELP as RULES_HELP
from racer_tui.cli.rules_option import rules_option
from sim.foundation.plural import counted
from sim.foundation.remedies import RemedyError
from sim.race.rules import (
    DEFAULT_RULES,
    RULE_PRESETS,
    RankingMethod,
    RulesError,
    Verification,
    preset_rules,
    rules_from_mapping,
)
from sim.tracks.catalog import DEFAULT_TRACK

if TYPE_CHECKING:
    from league.leaderboard import LeaderboardRow
    from league.report import Column as ReportColumn
    from league.store import League

    Parsers = argparse._SubParsersAction[argparse.ArgumentParser]

NAMES = ("submit", "leaderboard", "night", "season", "racer", "correct")
FORMATS = ("table", "json", "csv", "markdown")


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
        choices=OPTION_CHOICES,
        help="which of a track's boards: time-trial (the default with --track), "
        "object-avoidance or head-to-bot; without --track, every race type's boards",
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
    board.add_argument("--format", choices=FORMATS, default="table")


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
    key_commands.register(actions, db)


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


# --- dispatch ------------------------------------------------------------------------------------


def run(args: argparse.Namespace) -> int | AppLaunch:
    from league.opening import open_league

    handlers: dict[str, Callable[[League, argparse.Namespace], int]] = {
        "submit": _submit,
        "leaderboard": _leaderboard,
        "night": _night,
        "season": _season,
        "racer": _racer,
        "correct": _correct,
    }
    if args.command == "night" and args.night_command == "projector":
        return _night_projector(args)
    with open_league(args.db) as league:
        return handlers[args.command](league, args)


def _night_projector(args: argparse.Namespace) -> AppLaunch:
    """The app, straight on a night's projector: for the venue's screen, in a terminal of
    its own beside the host's racer-tui. A kiosk: only q then y leaves, and it ends the
    program rather than open the rest of the app on the venue's screen."""
    from league.nights import get_night
    from league.opening import open_league
    from sim.foundation.home import LEAGUE_ENV

    with open_league(args.db) as league:
        night = get_night(league, args.night)  # a wrong name is one sentence, before the app
    if args.db:  # the whole app, not only the projector, on that league (as --db does)
        os.environ[LEAGUE_ENV] = str(args.db)
    # The entry point opens the app (run_app: a crash on the venue's screen is reported and
    # ends non-zero, as the app's).
    return AppLaunch(projector_night=night.id, db_path=args.db)


def _table(title: str) -> Table:
    """A table without vertical rules (a leaderboard's eight columns fit 80 characters).
    Titles carry night and season names, so they are plain Text, never markup."""
    return Table(
        title=Text(title, style="table.title"),
        box=box.SIMPLE_HEAD,
        pad_edge=False,
        collapse_padding=True,
    )


def _text(value: str) -> Text:
    return Text(value)


def _submit(league: League, args: argparse.Namespace) -> int:
    from league.submissions import submit_model

    submission, outcome = submit_model(
        league,
        args.model,
        args.racer,
        track=args.track,
        evaluation=args.evaluation,
        model_name=args.model_name,
        allow_stale=args.stale_ok,
    )
    best = submission.best_lap
    if args.json:
        print_json(
            {
                "id": outcome.submission_id,
                "duplicate": outcome.duplicate,
                "racer": submission.racer,
                "model": submission.model_name,
                "track": submission.track_name,
                "source": submission.source,
                "race_type": submission.race_type,
                "best_lap": best,
                "laps": len(submission.completed_laps),
                "trials": len(submission.laps),
            }
        )
        return 0
    if outcome.duplicate:
        print(f"Already in the league as {outcome.submission_id}; nothing added.")
        return 0
    from league.race_types import TIME_TRIAL, board_name

    lap_text = "no completed lap" if best is None else f"best lap {best:.3f} s"
    # Said when it is not a time trial: its laps go on that race type's board.
    where = board_name(submission.track_name, submission.physics, submission.race_type)
    if submission.race_type == TIME_TRIAL:
        where = submission.track_name
    print(
        f"Submitted {submission.model_name} for {submission.racer} on {where}: "
        f"{lap_text}, {len(submission.completed_laps)} of {len(submission.laps)} trials "
        f"completed (id {outcome.submission_id})."
    )
    return 0


def _leaderboard(league: League, args: argparse.Namespace) -> int:
    from league.leaderboard import (
        Filters,
        board_of,
        leaderboard,
        mark_verification,
        method_for,
        several_boards,
        sort_rows,
    )
    from league.nights import get_night, list_nights
    from league.race_types import TIME_TRIAL, parse_race_type
    from league.racers import get_racer
    from league.report import (
        leaderboard_columns,
        leaderboard_json,
        to_csv,
        to_markdown,
    )
    from league.seasons import get_season
    from league.tracks import track_for

    night_ids: list[str] | None = None
    if args.night:
        night_ids = [get_night(league, args.night).id]
    if args.season:
        season = get_season(league, args.season)
        season_nights = [night.id for night in list_nights(league) if night.season_id == season.id]
        night_ids = (
            season_nights
            if night_ids is None
            else [night for night in night_ids if night in season_nights]
        )
    track = track_for(league, args.track) if args.track else None
    # A track's board is its time trials' unless --race-type picks another; a night's races
    # are of the night's race type, and a listing of every track shows every board.
    race_type = (
        parse_race_type(args.race_type)
        if args.race_type
        else (TIME_TRIAL if track is not None and night_ids is None else None)
    )
    models_here = _models_here()
    filters = Filters(
        track_hash=track.track_hash if track is not None else None,
        racer=get_racer(league, args.racer).name if args.racer else None,
        night_ids=night_ids,
        race_type=race_type,
        verification=Verification(args.verification),
        local_models=models_here,
    )
    # A night's races rank by the night's own rules unless --by says otherwise.
    method = (
        method_for(args.by) if args.by else (None if night_ids is not None else method_for("best"))
    )
    rows = leaderboard(league, filters, method)
    said = False
    if not rows and track is not None and race_type is not None:
        said = _other_boards(
            league, track.track_hash, track.name, race_type, args.format == "table"
        )
    rows = sort_rows(rows, args.sort, reverse=args.reverse)
    if args.limit is not None:
        if args.limit < 1:
            raise LeagueError("--limit must be at least 1.")
        rows = rows[: args.limit]
    mark_verification(league, rows, models_here)
    shown_method = method if method is not None else _night_method(league, night_ids)
    show_track = several_boards(rows)
    if args.format == "json":
        print_json(leaderboard_json(rows, shown_method))
        return 0
    columns = leaderboard_columns(
        shown_method, show_track=show_track, iso_times=args.format == "csv", verification=True
    )
    if args.format == "csv":
        sys.stdout.write(to_csv(columns, rows))
    elif args.format == "markdown":
        sys.stdout.write(to_markdown(columns, rows))
    else:
        # One table per board: a track under one race type and one physics, ranked alone.
        boards: dict[tuple[str, str, str], list[LeaderboardRow]] = {}
        for row in rows:
            boards.setdefault(board_of(row), []).append(row)
        if not rows:
            if not said:
                print(_no_laps(track.name if track is not None else None, race_type))
            return 0
        single = len(boards) == 1 or args.sort != "rank"
        groups = [rows] if single else list(boards.values())
        for group in groups:
            _print_board(group, columns if single else _without_track(columns), shown_method)
    return 0


def _no_laps(track_name: str | None, race_type: str | None) -> str:
    """What an empty table says, and how laps get there."""
    from league.race_types import words

    kind = "" if race_type is None else f"{words(race_type).replace(' ', '-')} "
    where = f" on {track_name}" if track_name is not None else " in this league"
    return (
        f"No {kind}laps{where} yet: record a race with racer-tui --race MODEL --record, "
        "or submit an evaluation with racer-tui submit."
    )


def _other_boards(
    league: League, track_hash: str, track_name: str, race_type: str, on_stdout: bool
) -> bool:
    """Say which race types a track has laps of, when the board asked for has none (on
    stderr beside JSON, CSV or Markdown, which stay the data alone); False when it has
    none at all."""
    from league.leaderboard import race_types_on
    from league.race_types import words

    others = [kind for kind in race_types_on(league, track_hash) if kind != race_type]
    if not others:
        return False
    options = " or ".join(f"--race-type {option_name(kind)}" for kind in others)
    print(
        f"No {words(race_type).replace(' ', '-')} laps on {track_name} yet; its other "
        f"board{'s' if len(others) > 1 else ''}: {options}.",
        file=sys.stdout if on_stdout else sys.stderr,
    )
    return True


def _print_board(
    rows: Sequence[LeaderboardRow], columns: Sequence[ReportColumn], method: RankingMethod
) -> None:
    from league.report import SCORE_TITLES

    tracks = sorted({row.track_name for row in rows})
    where = f"{tracks[0]}, " if len(tracks) == 1 else ""
    table = _table(f"Leaderboard: {where}ranked by {SCORE_TITLES[method]}")
    for column in columns:
        # Names get room first; on a narrow terminal the headers of numbers wrap.
        named = column.title in ("racer", "model", "track")
        table.add_column(
            column.title,
            justify="right" if column.numeric else "left",
            min_width=8 if named else None,
        )
    for row in rows:
        table.add_row(*(_text(column.cell(row)) for column in columns))
    print_table(table)


def _without_track(columns: Sequence[ReportColumn]) -> list[ReportColumn]:
    return [column for column in columns if column.title != "track"]


def _night_method(league: League, night_ids: Sequence[str] | None) -> RankingMethod:
    from league.nights import get_night

    if night_ids:
        return get_night(league, night_ids[0]).rules.ranking
    return DEFAULT_RULES.ranking


def _models_here() -> frozenset[str]:
    """The garage's model hashes: their results are verifiable here."""
    from sim.training.drivers import DriversByHash

    return DriversByHash().models_here()


# --- nights ----------------------------------------------------------------------------------


def _night(league: League, args: argparse.Namespace) -> int:
    from league import nights
    from league.local_racer import HOST_NAME, local_racer_name

    action = args.night_command
    if action == "new":
        from sim.tracks.catalog import resolve_track

        rules = rules_option(args.rules) if args.rules else DEFAULT_RULES
        if args.preset is not None:
            rules = preset_rules(args.preset)
        if args.laps is not None:
            try:
                rules = rules_from_mapping({"lap_count": args.laps}, base=rules)
            except RulesError as error:
                raise RulesError(f"--laps: {error}") from None
        if args.verification is not None:
            rules = rules_from_mapping({"verification": args.verification}, base=rules)
        held_on = nights.night_date(args.date) if args.date is not None else None
        night = nights.new_night(
            league,
            resolve_track(args.track),
            rules=rules,
            name=args.name,
            season=args.season,
            held_on=held_on,
        )
        print(
            f"Opened league night {night.name} ({night.id}) on {night.track_name}, {night.held_on}."
        )
        print(f"Rules (frozen): {night.rules.describe()}.")
        return 0
    if action == "list":
        return _night_list(league, args.json)
    night = nights.get_night(league, args.night)
    if action == "add":
        entrant = nights.add_entrant(league, night, args.racer, args.model)
        print(f"Entered {entrant.racer} with {entrant.model} ({entrant.id}).")
        return 0
    if action == "draw":
        order = nights.draw_heats(league, night, args.seed)
        for heat in order:
            if heat.race_id is None:
                print(f"heat {heat.position}: {heat.entrant.display_name} ({heat.entrant.model})")
        return 0
    if action == "run":
        return _night_run(league, night, args.heats)
    if action == "withdraw":
        entrant = nights.find_entrant(league, night, args.racer, args.model)
        who = args.by or local_racer_name(league) or HOST_NAME
        nights.withdraw_entrant(league, night, entrant.id, who)
        print(f"Withdrew {entrant.display_name} ({entrant.model}) from {night.name}.")
        return 0
    if action == "move":
        return _night_move(league, night, args)
    if action == "delete":
        who = args.by or local_racer_name(league) or HOST_NAME
        nights.delete_night(league, night, who)
        print(f"Deleted league night {night.name} ({night.id}).")
        return 0
    if action == "close":
        return _night_close(league, night, args)
    return _night_show(league, night, "json" if args.json else args.format)


def _night_close(league: League, night: Any, args: argparse.Namespace) -> int:
    """Close the night; under a verification rule, race its simulated heats again here
    first, and say of each heat withdrawn or left out of the standings why (on stderr
    beside --json, which stays the standings alone)."""
    from league import nights
    from league.local_racer import HOST_NAME, local_racer_name
    from league.night_verification import uncounted_heats
    from league.nights import replay_heats
    from sim.training.drivers import DriversByHash

    who = args.by or local_racer_name(league) or HOST_NAME
    drivers = DriversByHash()
    said = sys.stderr if args.json else sys.stdout
    # Raced again here rather than by close_night, so what came out is said before a heat
    # it withdrew holds the night open (a closed night is refused by close_night as ever).
    if night.rules.verification.requires and not night.closed:
        for sentence in replay_heats(league, night, drivers):
            print(sentence, file=said)
    standings = nights.close_night(league, night, who, force=args.force)
    models_here = drivers.models_here()
    for sentence in uncounted_heats(league, night, models_here):
        print(sentence, file=said)
    return _print_standings(
        league,
        night,
        standings,
        args.json,
        f"{night.name}: final standings",
        models_here=models_here,
    )


def _night_move(league: League, night: Any, args: argparse.Namespace) -> int:
    from league import nights

    entrant = nights.find_entrant(league, night, args.racer, args.model)
    waiting = nights.pending_heats(league, night)
    index = next((i for i, heat in enumerate(waiting) if heat.entrant.id == entrant.id), None)
    if index is None:
        if any(heat.entrant.id == entrant.id for heat in nights.heats(league, night)):
            raise LeagueError(f"{entrant.display_name} has raced; only a waiting heat moves.")
        raise LeagueError(
            f"{entrant.display_name} has no heat waiting on {night.name}; draw the heats "
            "first (`racer-tui night draw`)."
        )
    if not 1 <= args.to <= len(waiting):
        raise LeagueError(f"--to must be from 1 to {len(waiting)}, the heats still to race.")
    if args.to - 1 == index:
        raise LeagueError(f"{entrant.display_name}'s heat is already number {args.to} to race.")
    order = nights.move_heat(league, night, waiting[index].id, args.to - 1 - index)
    print("Still to race, in order (--to counts these):")
    for place, heat in enumerate((h for h in order if h.race_id is None), start=1):
        print(f"{place}. heat {heat.position}: {heat.entrant.display_name} ({heat.entrant.model})")
    return 0


def _night_list(league: League, as_json: bool) -> int:
    from league.nights import list_nights
    from league.race_types import race_type_of

    found = list_nights(league)
    if as_json:
        print_json(
            [
                {
                    "id": n.id,
                    "name": n.name,
                    "track": n.track_name,
                    "season_id": n.season_id,
                    "closed": n.closed,
                    "held_on": n.held_on,
                    "created_at": n.created_at,
                    "race_type": race_type_of(n.rules),
                    "rules": n.rules.to_dict(),
                }
                for n in found
            ]
        )
        return 0
    table = _table("League nights")
    for title in ("id", "name", "track", "state", "date"):
        table.add_column(title)
    for n in found:
        state = "closed" if n.closed else "open"
        table.add_row(n.id, _text(n.name), _text(n.track_name), state, n.held_on)
    print_table(table)
    return 0


def _night_run(league: League, night: Any, limit: int | None) -> int:
    from league.nights import find_night_track, run_heats, timekept_heats

    try:
        race_commands = importlib.import_module("racer_tui.cli.race_commands")
        load_driver = race_commands.resolve_driver
    except (ImportError, AttributeError):
        raise LeagueError(
            "this racer-tui cannot load drivers for heats (racer_tui.cli.race_commands."
            "resolve_driver is missing); update racer-tui."
        ) from None

    def resolve_driver(spec: str, track: Any) -> Any:
        try:
            return load_driver(spec, track)
        except RemedyError as error:  # one sentence, with the night's context
            raise LeagueError(f"cannot run the heat with {spec!r}: {error}") from None

    track = find_night_track(night)

    def report(heat: Any, result: Any) -> None:
        best = result.best_lap
        lap = "no valid lap" if best is None else f"best lap {best.time_seconds:.3f} s"
        print(
            f"heat {heat.position}: {heat.entrant.display_name} ({heat.entrant.car}) "
            f"{lap}, {counted(result.valid_laps, 'valid lap')}, "
            f"{counted(result.total_offtracks, 'off-track')}",
            flush=True,
        )

    run_heats(league, night, track, resolve_driver, on_result=report, limit=limit)
    for heat in timekept_heats(league, night):
        print(
            f"heat {heat.position}: {heat.entrant.display_name}'s physical car waits for a "
            "timekeeper: run it in the app (r on the Nights screen).",
            flush=True,
        )
    return 0


def _night_show(league: League, night: Any, kind: str) -> int:
    from league import nights
    from league.leaderboard import mark_verification
    from league.night_report import night_export
    from league.night_verification import uncounted_heats

    entrants = nights.entrants(league, night)
    heats = nights.heats(league, night)
    models_here = _models_here()
    standings = nights.standings(league, night, local_models=models_here)
    if kind != "table":
        mark_verification(league, [s.entry for s in standings], models_here)
        print(night_export(night, entrants, heats, standings, kind), end="")
        return 0
    state = "closed" if night.closed else "open"
    print(f"{night.name} ({night.id}) on {night.track_name}, {night.held_on}, {state}.")
    print(f"Rules: {night.rules.describe()}.")
    print(f"Entrants: {len(entrants)}; heats raced: {sum(h.race_id is not None for h in heats)}")
    if heats:
        table = _table("Heats")
        for title in ("heat", "racer", "model", "race"):
            table.add_column(title)
        for i, heat in enumerate(heats, start=1):
            table.add_row(
                str(i),
                _text(heat.entrant.display_name),
                _text(heat.entrant.model),
                heat.race_id or "waiting",
            )
        print_table(table)
    for sentence in uncounted_heats(league, night, models_here):
        print(sentence)
    return _print_standings(
        league, night, standings, False, f"{night.name}: standings", models_here=models_here
    )


def _print_standings(
    league: League,
    night: Any,
    standings: Sequence[Any],
    as_json: bool,
    title: str,
    *,
    models_here: frozenset[str],
) -> int:
    from league.leaderboard import mark_verification
    from league.report import SCORE_TITLES, seconds

    mark_verification(league, [s.entry for s in standings], models_here)
    if as_json:
        from league.night_report import standings_json

        print_json(standings_json(standings))
        return 0
    table = _table(title)
    table.add_column("pos", justify="right")
    table.add_column("racer")
    table.add_column("model")
    table.add_column(SCORE_TITLES[night.rules.ranking], justify="right")
    table.add_column("laps", justify="right")
    table.add_column("off-tracks", justify="right")
    table.add_column("points", justify="right")
    table.add_column("verification")
    for s in standings:
        table.add_row(
            "-" if s.position is None else str(s.position),
            _text(s.entry.display_name),
            _text(s.entry.model),
            seconds(s.entry.score),
            str(s.entry.valid_laps),
            str(s.entry.offtracks),
            str(s.points),
            s.entry.verification,
        )
    print_table(table)
    return 0


# --- seasons, racers, corrections ---------------------------------------------------------------


def _season(league: League, args: argparse.Namespace) -> int:
    from league import seasons

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
        table = _table("Seasons")
        for title in ("id", "name", "points"):
            table.add_column(title)
        for found_season in found:
            table.add_row(
                found_season.id,
                _text(found_season.name),
                "-".join(str(p) for p in found_season.points),
            )
        print_table(table)
        return 0
    season = seasons.get_season(league, args.season)
    standings = seasons.season_standings(league, season)
    if args.json:
        print_json(
            {
                "id": season.id,
                "name": season.name,
                "points": list(season.points),
                "nights": len(seasons.closed_nights(league, season)),
                "standings": [
                    {
                        "position": s.position,
                        "racer": s.display_name,
                        "racer_name": s.racer,
                        "points": s.points,
                        "nights": s.nights,
                        "wins": s.wins,
                    }
                    for s in standings
                ],
            }
        )
        return 0
    nights_closed = len(seasons.closed_nights(league, season))
    table = _table(f"Season {season.name}: {counted(nights_closed, 'closed night')}")
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
            str(s.position), _text(s.display_name), str(s.points), str(s.nights), str(s.wins)
        )
    print_table(table)
    return 0


def _racer(league: League, args: argparse.Namespace) -> int:
    from league import racers
    from league.racers import HEX_COLOUR

    action = args.racer_command
    if action in key_commands.ACTIONS:
        return key_commands.run(league, args)
    if action == "add":
        racer = racers.add_racer(
            league, args.name, display_name=args.display_name, colour=args.colour
        )
        print(f"Added racer {racer.name}.")
        return 0
    if action == "rename":
        from league.corrections import rename_racer

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
    table = _table("Racers")
    for title in ("name", "shown as", "colour"):
        table.add_column(title)
    for r in found:
        # Colours may come from other racers' machines: only a checked #rrggbb is a style.
        style = r.colour if HEX_COLOUR.fullmatch(r.colour) else ""
        table.add_row(_text(r.name), _text(r.display_name), Text(r.colour, style=style))
    print_table(table)
    return 0


def _correct(league: League, args: argparse.Namespace) -> int:
    from league.corrections import disqualify_lap, list_corrections

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
    table = _table("Corrections")
    for title in ("id", "what", "target", "by", "why", "when"):
        table.add_column(title)
    for c in found:
        what = (
            f"lap {c.lap_number} disqualified"
            if c.kind == "disqualify_lap"
            else (f"shown as {c.new_value}")
        )
        table.add_row(
            c.id, _text(what), _text(c.target), _text(c.made_by), _text(c.reason), c.created_at[:16]
        )
    print_table(table)
    return 0

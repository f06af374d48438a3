"""`racer-tui night ...`: open a night, enter cars, draw, run and close heats, show it."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from typing import Any

from rich.text import Text

from league import nights
from league.bracket_records import read_bracket
from league.errors import LeagueError
from league.leaderboard import mark_verification
from league.local_racer import HOST_NAME, local_racer_name
from league.night_report import night_export, standing_car, standings_json
from league.night_verification import uncounted_heats
from league.nights import (
    find_night_track,
    get_night,
    list_nights,
    replay_heats,
    run_heats,
    timekept_heats,
)
from league.opening import open_league
from league.race_types import race_type_of
from league.report import SCORE_TITLES, seconds
from league.store import League
from league.timekeeper.car import PHYSICAL, is_physical
from racer_tui.cli.app_launch import AppLaunch
from racer_tui.cli.league_commands.board import garage_model_hashes
from racer_tui.cli.league_commands.brackets import bracket_command, match_command, print_bracket
from racer_tui.cli.output import plain_table, print_json, print_table
from racer_tui.cli.rules_option import rules_option
from sim.foundation.home import LEAGUE_ENV
from sim.foundation.plural import counted
from sim.foundation.remedies import RemedyError
from sim.garage.folder import list_models
from sim.race.rules import DEFAULT_RULES, RulesError, preset_rules, rules_from_mapping
from sim.tracks.catalog import resolve_track
from sim.training.drivers import DriversByHash, resolve_driver


def run(args: argparse.Namespace) -> int | AppLaunch:
    if args.night_command == "projector":
        return projector(args)
    with open_league(args.db) as league:
        return night_command(league, args)


def projector(args: argparse.Namespace) -> AppLaunch:
    """The app, straight on a night's projector: for the venue's screen, in a terminal of
    its own beside the host's racer-tui. A kiosk: only q then y leaves, and it ends the
    program rather than open the rest of the app on the venue's screen."""

    with open_league(args.db) as league:
        night = get_night(league, args.night)  # a wrong name is one sentence, before the app
    if args.db:  # the whole app, not only the projector, on that league (as --db does)
        os.environ[LEAGUE_ENV] = str(args.db)
    # The entry point opens the app (run_app: a crash on the venue's screen is reported and
    # ends non-zero, as the app's).
    return AppLaunch(projector_night=night.id, db_path=args.db)


def night_command(league: League, args: argparse.Namespace) -> int:

    action = args.night_command
    if action == "new":
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
        others = [e for e in nights.entrants(league, night) if e.id != entrant.id]
        note = nights.entrant_note(
            entrant.model,
            training={folder.name for folder in list_models() if folder.is_training()},
            physical_rules=night.rules == preset_rules(PHYSICAL),
            physical_entered=any(is_physical(other.model) for other in others),
        )
        if note:
            print(f"Note: {note}")
        return 0
    if action == "draw":
        order = nights.draw_heats(league, night, args.seed)
        for heat in order:
            if heat.race_id is None:
                print(f"heat {heat.position}: {heat.entrant.display_name} ({heat.entrant.model})")
        if any(heat.race_id is None and is_physical(heat.entrant.model) for heat in order):
            print(
                "A physical car's heat waits for its timekeeper (r on the Nights screen); "
                "heats raced before it move ahead of it in the running order."
            )
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
    if action == "bracket":
        return bracket_command(league, night, args)
    if action == "match":
        return match_command(league, night, args.matches)
    return _night_show(league, night, "json" if args.json else args.format)


def _night_close(league: League, night: Any, args: argparse.Namespace) -> int:
    """Close the night; under a verification rule, race its simulated heats again here
    first, and say of each heat withdrawn or left out of the standings why (on stderr
    beside --json, which stays the standings alone)."""

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
    table = plain_table("League nights")
    for title in ("id", "name", "track", "state", "date"):
        table.add_column(title)
    for n in found:
        state = "closed" if n.closed else "open"
        table.add_row(n.id, Text(n.name), Text(n.track_name), state, n.held_on)
    print_table(table)
    return 0


def _night_run(league: League, night: Any, limit: int | None) -> int:

    def entrant_driver(spec: str, track: Any) -> Any:
        try:
            return resolve_driver(spec, track)
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

    run_heats(league, night, track, entrant_driver, on_result=report, limit=limit)
    for heat in timekept_heats(league, night):
        print(
            f"heat {heat.position}: {heat.entrant.display_name}'s physical car waits for a "
            "timekeeper: run it in the app (r on the Nights screen).",
            flush=True,
        )
    return 0


def _night_show(league: League, night: Any, kind: str) -> int:

    entrants = nights.entrants(league, night)
    heats = nights.heats(league, night)
    models_here = garage_model_hashes()
    standings = nights.standings(league, night, local_models=models_here)
    if kind != "table":
        mark_verification(league, [s.entry for s in standings], models_here)
        drawn = read_bracket(league, night.id)
        print(night_export(night, entrants, heats, standings, kind, bracket=drawn), end="")
        return 0
    state = "closed" if night.closed else "open"
    print(f"{night.name} ({night.id}) on {night.track_name}, {night.held_on}, {state}.")
    print(f"Rules: {night.rules.describe()}.")
    print(f"Entrants: {len(entrants)}; heats raced: {sum(h.race_id is not None for h in heats)}")
    if heats:
        table = plain_table("Heats")
        for title in ("heat", "racer", "car", "race"):
            table.add_column(title)
        for i, heat in enumerate(heats, start=1):
            table.add_row(
                str(i),
                Text(heat.entrant.display_name),
                Text(heat.entrant.car),  # a bundle's file name, not its whole path
                heat.race_id or "waiting",
            )
        print_table(table)
    for sentence in uncounted_heats(league, night, models_here):
        print(sentence)
    print_bracket(league, night)
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

    mark_verification(league, [s.entry for s in standings], models_here)
    if as_json:
        print_json(standings_json(standings))
        return 0
    table = plain_table(title)
    table.add_column("pos", justify="right")
    table.add_column("racer")
    table.add_column("car")
    table.add_column(SCORE_TITLES[night.rules.ranking], justify="right")
    table.add_column("laps", justify="right")
    table.add_column("off-tracks", justify="right")
    table.add_column("points", justify="right")
    table.add_column("verification")
    for s in standings:
        table.add_row(
            "-" if s.position is None else str(s.position),
            Text(s.entry.display_name),
            Text(standing_car(s)),
            seconds(s.entry.score),
            str(s.entry.valid_laps),
            str(s.entry.offtracks),
            str(s.points),
            s.entry.verification,
        )
    print_table(table)
    return 0

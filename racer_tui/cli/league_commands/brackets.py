"""`racer-tui night bracket` and `night match`: a night's knock-out bracket from its
qualifying, and its matches raced headless (league.bracket_nights)."""

from __future__ import annotations

import argparse

from rich.text import Text

from league.bracket_nights import (
    MatchCars,
    bracket_rules,
    draw_night_bracket,
    left_out_note,
    match_entries,
    match_seed,
    next_match,
    record_match,
)
from league.bracket_records import NightBracket, read_bracket
from league.brackets import BYE, Format
from league.errors import LeagueError
from league.nights import Night, entrants, find_night_track
from league.store import League
from racer_tui.cli.output import plain_table, print_table
from sim.foundation.plural import counted
from sim.race.head_to_head import HeadToHeadResult, run_head_to_head
from sim.race.rules import RulesError
from sim.tracks.track import Track
from sim.training.drivers import resolve_driver


def bracket_command(league: League, night: Night, args: argparse.Namespace) -> int:
    if args.laps is None or not 1 <= args.laps <= 99:
        raise RulesError(f"--laps: a match is 1 to 99 laps, not {args.laps}.")
    rules = bracket_rules(night, args.laps, physical=args.physical)
    form = Format.DOUBLE if args.double else Format.SINGLE
    drawn = draw_night_bracket(
        league, night, format=form, size=args.size, rules=rules, physical=args.physical
    )
    kind = "double" if args.double else "single"
    cars = "physical cars, " if args.physical else ""
    won = "the first to finish, penalties added" if args.physical else "first past the line"
    print(
        f"Drew {night.name}'s {kind}-elimination bracket of {len(drawn.bracket.seeds)} "
        f"{cars}from its standings; each match {counted(args.laps, 'lap')}, {won}."
    )
    note = left_out_note(league, night)
    if note:
        print(note)
    print_bracket(league, night, drawn)
    return 0


def match_command(league: League, night: Night, limit: int | None) -> int:
    if limit is not None and limit < 1:
        raise LeagueError(f"--matches must be at least 1, not {limit}.")
    track = find_night_track(night)
    drawn = read_bracket(league, night.id)
    raced = 0
    while limit is None or raced < limit:
        cars = next_match(league, night)
        if cars is None:
            break
        if cars.physical:
            raise LeagueError(
                f"match {cars.match.id} is between physical cars ({cars.first.display_name} v "
                f"{cars.second.display_name}): time it on the real track in the app's Nights "
                "screen (r), a lap key for each car."
            )
        assert drawn is not None  # next_match found the bracket
        result = _race(track, drawn, cars)
        record_match(league, night, cars.match.id, result)
        raced += 1
        print(match_line(cars.match.id, result), flush=True)
    if raced == 0 and next_match(league, night) is None:
        print(f"{night.name}'s bracket is decided: no match is left to race.")
    decided = read_bracket(league, night.id)
    order = decided.final_order() if decided is not None else None
    if decided is not None and order is not None:
        shown = {e.id: e.display_name for e in entrants(league, night)}
        places = ", ".join(f"{k}. {shown.get(e, e)}" for k, e in enumerate(order, start=1))
        print(f"Champion: {shown.get(order[0], order[0])}. Final order: {places}.")
        if not night.closed:
            print("Close the night to make it final: `racer-tui night close`.")
    return 0


def _race(track: Track, drawn: NightBracket, cars: MatchCars) -> HeadToHeadResult:
    grid = match_entries(cars, track, resolve_driver)
    return run_head_to_head(track, drawn.rules, grid, seed=match_seed(drawn, cars.match.id))


def match_line(match_id: str, result: HeadToHeadResult) -> str:
    winner, loser = result.cars[0], result.cars[1]
    margin = "" if loser.gap_seconds is None else f" by {loser.gap_seconds:.3f} s"
    return (
        f"{match_id}: {winner.result.racer} ({winner.result.model_name}) beat "
        f"{loser.result.racer} ({loser.result.model_name}){margin}"
    )


def print_bracket(league: League, night: Night, drawn: NightBracket | None = None) -> None:
    """The bracket's matches: who races whom, and who won."""
    drawn = drawn or read_bracket(league, night.id)
    if drawn is None:
        return
    shown = {e.id: e.display_name for e in entrants(league, night)}
    winners = drawn.winners

    def name(side: str | None) -> Text:
        if side is None:
            return Text("to be decided", style="dim")
        return Text("bye", style="dim") if side == BYE else Text(shown.get(side, side))

    table = plain_table(f"{night.name}: bracket")
    for title in ("match", "racer", "v", "racer", "winner"):
        table.add_column(title)
    for match in drawn.bracket.matches:
        a, b = drawn.sides(match)
        winner = winners.get(match.id)
        decided = Text(shown.get(winner, winner)) if winner else Text("-", style="dim")
        table.add_row(match.id, name(a), "v", name(b), decided)
    print_table(table)

"""Bracket nights: a night's time trials are its qualifying, then its best race a knock-out.

AWS's Virtual Circuit ran head-to-head brackets this way: a qualifying seeds the bracket,
then models race two at a time and the winner goes on. Here a night is first raced as
every night is, its heats time trials; once every heat is raced the host draws the bracket
(`draw_night_bracket`): the night's standings are its seeds, best first (the top `size`
of them, or every racer with a counting result). Each match is a head-to-head race of its
two entrants' cars under the bracket's rules, recorded as a head-to-head race naming the
night and the match (`record_match`); the car first past the line wins it. The bracket's
final order is then the night's places and season points (league.bracket_records).

A bracket races one kind of car: simulated cars race each other in the simulator, and
physical cars on the real track, each match timed by hand for both cars at once
(league.timekeeper.match). The host draws it from the night's simulated qualifiers (the
default) or its physical ones (`physical`); the other kind is left out, and `qualifiers`
says which, for the front ends to tell the host.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, replace

from league.bracket_records import NightBracket, has_bracket, read_bracket, store_bracket
from league.brackets import MAX_ENTRANTS, MIN_ENTRANTS, Format, Match
from league.errors import LeagueError
from league.head_to_heads import record_head_to_head
from league.nights import (
    Entrant,
    Night,
    ResolveDriver,
    entrants,
    heats,
    pending_heats,
    standings,
)
from league.store import League
from league.timekeeper.car import is_physical
from sim.foundation.plural import counted
from sim.foundation.remedies import RemedyError
from sim.physics.objects.settings import RaceType
from sim.race.driver import Driver
from sim.race.head_to_head import Entry, HeadToHeadResult
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.track import Track


@dataclass(frozen=True)
class MatchCars:
    """A match to race: its two entrants, the higher seed first (the front of the grid)."""

    match: Match
    first: Entrant
    second: Entrant

    @property
    def physical(self) -> bool:
        """Two physical cars: the match is timed by hand on the real track."""
        return is_physical(self.first.model)


def bracket_rules(night: Night, laps: int, *, physical: bool = False) -> RaceRules:
    """Every match's rules: simapp's head-to-head over `laps` laps; a physical bracket's
    resets cost what the night's rules say (the `physical` preset adds no time), since
    its cars are timed as the night's heats were."""
    rules = replace(HEAD_TO_HEAD_RULES, lap_count=laps)
    if physical:
        rules = replace(rules, penalty_seconds=night.rules.penalty_seconds)
    return rules


def draw_night_bracket(
    league: League,
    night: Night,
    *,
    format: Format = Format.SINGLE,
    size: int | None = None,
    rules: RaceRules = HEAD_TO_HEAD_RULES,
    physical: bool = False,
) -> NightBracket:
    """Seed the night's bracket from its standings and store it (once per night): its
    simulated qualifiers, or its physical ones (`physical`)."""
    if rules.race_type is not RaceType.HEAD_TO_MODEL:
        raise LeagueError("a bracket's matches are head-to-head races: give head-to-head rules.")
    with league.transaction():
        if night.closed or league.query_one(
            "SELECT 1 FROM night_closures WHERE night_id = ?", (night.id,)
        ):
            raise LeagueError(f"league night {night.name!r} is closed; its results are final.")
        if has_bracket(league, night.id):
            raise LeagueError(f"league night {night.name!r} has its bracket drawn already.")
        waiting = len(pending_heats(league, night))
        raced = {heat.entrant.id for heat in heats(league, night)}
        undrawn = [e for e in entrants(league, night) if e.id not in raced]
        if waiting or undrawn:
            raise LeagueError(still_qualifying(night, waiting + len(undrawn)))
        seeds = _qualified(league, night, size, physical)
        drawn_id = store_bracket(league, night.id, [e.id for e in seeds], format, rules)
        drawn = read_bracket(league, night.id)
    assert drawn is not None and drawn.id == drawn_id
    return drawn


def still_qualifying(night: Night, waiting: int) -> str:
    """Why `night`'s bracket cannot be drawn yet: `waiting` entrants have not raced."""
    return (
        f"league night {night.name!r} is still qualifying ({counted(waiting, 'entrant')} "
        f"{'has' if waiting == 1 else 'have'} not raced their heat); run its heats (or "
        "withdraw those entrants), then draw the bracket."
    )


def qualifiers(league: League, night: Night) -> tuple[list[Entrant], list[Entrant]]:
    """The entrants with a counting qualifying result, best first: the simulated cars and
    the physical ones (a bracket races one kind)."""
    by_race = {heat.race_id: heat.entrant for heat in heats(league, night) if heat.race_id}
    placed = [
        by_race[s.entry.record_id]
        for s in standings(league, night)
        if s.position is not None and s.entry.record_id in by_race
    ]
    physical = [entrant for entrant in placed if is_physical(entrant.model)]
    return [entrant for entrant in placed if entrant not in physical], physical


def left_out_note(league: League, night: Night) -> str:
    """The sentence telling the host which cars the night's bracket left out, the other
    kind than it races ("" for none, or no bracket)."""
    drawn = read_bracket(league, night.id)
    if drawn is None or not drawn.bracket.seeds:
        return ""
    simulated, physical = qualifiers(league, night)
    racing_physical = drawn.bracket.seeds[0] in {entrant.id for entrant in physical}
    left = simulated if racing_physical else physical
    if not left:
        return ""
    names = ", ".join(entrant.display_name for entrant in left)
    verb = "is" if len(left) == 1 else "are"
    after = " They are placed after the bracket's racers, in their qualifying order."
    if racing_physical:
        return (
            f"Simulated cars are left out of the bracket ({names} {verb}): its matches are "
            f"raced by physical cars on the real track.{after}"
        )
    return (
        f"Physical cars are left out of the bracket ({names} {verb}): its matches are "
        f"simulated races (draw it from the physical cars to race them on the track).{after}"
    )


def bracket_is_physical(league: League, night: Night) -> bool:
    """Whether the night's bracket races physical cars (its seeds are)."""
    drawn = read_bracket(league, night.id)
    if drawn is None or not drawn.bracket.seeds:
        return False
    by_id = {entrant.id: entrant for entrant in entrants(league, night)}
    first = by_id.get(drawn.bracket.seeds[0])
    return first is not None and is_physical(first.model)


def _qualified(league: League, night: Night, size: int | None, physical: bool) -> list[Entrant]:
    """The entrants the bracket seeds, best qualifier of its kind first."""
    simulated, physical_cars = qualifiers(league, night)
    placed, others = (physical_cars, simulated) if physical else (simulated, physical_cars)
    kind, other = ("physical", "simulated") if physical else ("simulated", "physical")
    count = len(placed) if size is None else size
    if not MIN_ENTRANTS <= count <= min(len(placed), MAX_ENTRANTS):
        left_out = (
            f", {other} cars left out ({', '.join(e.display_name for e in others)})"
            if others
            else ""
        )
        raise LeagueError(
            f"a bracket of {count} needs {count} racers with a counting qualifying result in "
            f"a {kind} car; league night {night.name!r} has {len(placed)}{left_out} (a "
            f"bracket takes {MIN_ENTRANTS} to {MAX_ENTRANTS})."
        )
    return placed[:count]


def next_match(league: League, night: Night) -> MatchCars | None:
    """The next match to race, with its two entrants; None when the bracket is decided
    (or there is none)."""
    drawn = read_bracket(league, night.id)
    if drawn is None:
        raise LeagueError(
            f"league night {night.name!r} has no bracket; draw it once its heats are raced."
        )
    match = drawn.next_match()
    if match is None:
        return None
    by_id = {entrant.id: entrant for entrant in entrants(league, night)}
    a, b = drawn.sides(match)
    if a not in by_id or b not in by_id:  # withdrawn since: cannot happen from here
        raise LeagueError(f"match {match.id} of league night {night.name!r} lost an entrant.")
    # The higher seed starts in front, whichever side the plan puts it on (a losers' round
    # pairs a dropped winner with a survivor in either order): between cars of one pace
    # the front of the grid wins, so it is the better qualifier's.
    seed = {entrant: rank for rank, entrant in enumerate(drawn.bracket.seeds)}
    first, second = sorted((a, b), key=lambda side: seed.get(side, len(seed)))
    return MatchCars(match, by_id[first], by_id[second])


def record_match(league: League, night: Night, match_id: str, result: HeadToHeadResult) -> str:
    """Record `result` as the night's match `match_id`: its two cars must be the match's
    entrants' (the first past the line wins it). Returns the race's id."""
    with league.transaction():
        drawn = read_bracket(league, night.id)
        if drawn is None:
            raise LeagueError(f"league night {night.name!r} has no bracket.")
        match = drawn.bracket.match(match_id)
        if match_id in drawn.races:
            raise LeagueError(f"match {match_id} of league night {night.name!r} is raced.")
        if match not in drawn.bracket.ready(drawn.winners):
            raise LeagueError(f"match {match_id} cannot be raced yet: who races in it is unknown.")
        wanted = {drawn.racers[side] for side in drawn.sides(match) if side}
        racers = {finish.result.racer for finish in result.cars}
        if len(result.cars) != 2 or racers != wanted:
            raise LeagueError(
                f"match {match_id} is {' v '.join(sorted(wanted))}; this race's cars are "
                f"{', '.join(sorted(racers))}."
            )
        return record_head_to_head(league, result, night_id=night.id, match_id=match_id)


def match_seed(drawn: NightBracket, match_id: str) -> int:
    """A match's own seed, the same on every machine (the race replays from its record)."""
    return zlib.crc32(f"{drawn.id}/{match_id}".encode()) % 2**31


def match_entries(cars: MatchCars, track: Track, resolve_driver: ResolveDriver) -> list[Entry]:
    """The match's grid, the higher seed in front; `resolve_driver(model spec, track)` is
    the front end's (the league never loads a policy). One model twice is one driver, which
    acts for both its cars in one batch."""
    drivers: dict[str, Driver] = {}
    for entrant in (cars.first, cars.second):
        if entrant.model not in drivers:
            try:
                drivers[entrant.model] = resolve_driver(entrant.model, track)
            except RemedyError as error:  # one sentence, naming the match
                raise LeagueError(
                    f"cannot race {cars.match.id} with {entrant.car!r}: {error}"
                ) from None
    return [Entry(entrant.racer, drivers[entrant.model]) for entrant in (cars.first, cars.second)]

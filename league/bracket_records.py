"""A night's knock-out bracket as the league keeps it, and the places it gives the night.

The bracket is one shared record per night (`brackets`): its format, its seeds (the night's
entrant ids, best qualifier first) and the rules every match races under. Its matches are
head-to-head records naming the night and the match (league.head_to_heads); a match's
winner is the car first past the line. Who races next and the final order follow from
those with league.brackets, the same on every machine.

What another machine recorded is read as it can count: the first bracket drawn for a night
(two hosts may each draw one before they sync), the first race recorded for a match, and a
match's race only when its cars are that match's two entrants as the bracket stands.
This module knows nothing of a night's heats (league.bracket_nights draws from them), so
the night's standings and the season (league.seasons) can read a bracket's places.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from league.brackets import BYE, Bracket, Format, Match, draw_bracket
from league.head_to_heads import RecordedHeadToHead, head_to_head_races
from league.leaderboard import LeaderboardRow
from league.store import League, now_iso
from sim.race.rules import RaceRules, rules_from_mapping

TABLE = "brackets"


@dataclass(frozen=True)
class NightBracket:
    id: str
    night_id: str
    bracket: Bracket  # its seeds are entrant ids
    rules: RaceRules  # every match's
    created_at: str
    racers: Mapping[str, str]  # entrant id -> racer
    races: Mapping[str, RecordedHeadToHead] = field(default_factory=dict)  # by match id

    @property
    def winners(self) -> dict[str, str]:
        """Each raced match's winning entrant id."""
        by_racer = {racer: entrant for entrant, racer in self.racers.items()}
        return {match: by_racer[race.winner] for match, race in self.races.items()}

    def next_match(self) -> Match | None:
        """The first match that can be raced now (both sides known); None when none can."""
        ready = self.bracket.ready(self.winners)
        return ready[0] if ready else None

    def sides(self, match: Match) -> tuple[str | None, str | None]:
        """The match's two entrant ids (BYE, or None while not known)."""
        return self.bracket.sides(match, self.winners)

    def final_order(self) -> list[str] | None:
        """Entrant ids, champion first, once the bracket is decided; None before."""
        return self.bracket.final_order(self.winners)


def store_bracket(
    league: League,
    night_id: str,
    seeds: Sequence[str],
    format: Format,
    rules: RaceRules,
) -> str:
    """Insert the night's bracket record (inside the caller's transaction); its id."""
    return league.insert_record(
        TABLE,
        {
            "night_id": night_id,
            "format": format.value,
            "seeds": json.dumps(list(seeds)),
            "rules": json.dumps(rules.to_dict(), sort_keys=True),
            "created_at": now_iso(),
        },
    )


def read_bracket(league: League, night_id: str) -> NightBracket | None:
    """The night's bracket (the first drawn) with the races of its matches, or None."""
    row = league.query_one(
        f"SELECT id, format, seeds, rules, created_at FROM {TABLE} "
        "WHERE night_id = ? ORDER BY created_at, id LIMIT 1",
        (night_id,),
    )
    if row is None:
        return None
    seeds = [str(seed) for seed in json.loads(row["seeds"])]
    marks = ", ".join("?" for _ in seeds)
    racers = {
        str(entrant["id"]): str(entrant["racer"])
        for entrant in league.query(  # the night's own: a pulled record names any id
            f"SELECT id, racer FROM night_entrants WHERE night_id = ? AND id IN ({marks})",
            (night_id, *seeds),
        )
    }
    bracket = draw_bracket(seeds, Format(row["format"]))
    drawn = NightBracket(
        id=row["id"],
        night_id=night_id,
        bracket=bracket,
        rules=rules_from_mapping(json.loads(row["rules"])),
        created_at=row["created_at"],
        racers=racers,
    )
    return _with_races(drawn, head_to_head_races(league, night_id=night_id))


def _with_races(drawn: NightBracket, recorded: Sequence[RecordedHeadToHead]) -> NightBracket:
    """The bracket with each match's counting race: the first recorded whose two cars are
    the match's entrants as the bracket stands after the matches before it."""
    by_match: dict[str, list[RecordedHeadToHead]] = {}
    for race in recorded:  # oldest first
        if race.match_id is not None:
            by_match.setdefault(race.match_id, []).append(race)
    races: dict[str, RecordedHeadToHead] = {}
    counted = drawn
    for match in drawn.bracket.matches:  # in the order they can be raced
        a, b = counted.sides(match)
        if not a or not b:  # not known yet, or a bye: no race counts for it
            continue
        wanted = {drawn.racers.get(a), drawn.racers.get(b)}
        for race in by_match.get(match.id, []):
            if len(race.places) == 2 and {place.racer for place in race.places} == wanted:
                races[match.id] = race
                counted = replace(counted, races=dict(races))
                break
    return counted


def bracket_places(league: League, night_ids: Sequence[str]) -> dict[str, list[str]]:
    """Each decided bracket's final order, as racers, by night id (nights without a
    bracket, or whose bracket is still being raced, are not in it)."""
    places: dict[str, list[str]] = {}
    for night_id in night_ids:
        drawn = read_bracket(league, night_id)
        order = drawn.final_order() if drawn is not None else None
        if drawn is not None and order is not None:
            named = (drawn.racers.get(entrant) for entrant in order if entrant != BYE)
            places[night_id] = [racer for racer in named if racer is not None]
    return places


def has_bracket(league: League, night_id: str) -> bool:
    return league.query_one(f"SELECT 1 FROM {TABLE} WHERE night_id = ?", (night_id,)) is not None


def with_bracket_places(
    rows: Sequence[LeaderboardRow], places: Mapping[str, Sequence[str]]
) -> list[LeaderboardRow]:
    """Nights' ranked rows (league.seasons.night_results) with each decided bracket's
    final order as its night's ranks: the bracket's entrants first, as it placed them, then
    the night's other racers in their qualifying order."""
    by_night: dict[str | None, list[LeaderboardRow]] = {}
    for row in rows:
        by_night.setdefault(row.night_id, []).append(row)
    result: list[LeaderboardRow] = []
    for night_id, night_rows in by_night.items():
        order = places.get(night_id) if night_id is not None else None
        if order is None:
            result.extend(night_rows)
            continue
        place = {racer: k for k, racer in enumerate(order)}
        placed = sorted(night_rows, key=lambda row: place.get(row.racer, len(order)))
        for rank, row in enumerate(placed, start=1):
            row.rank = rank
        result.extend(placed)
    return result

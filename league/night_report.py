"""A league night as a file: its standings with points as CSV or Markdown (the same
formatters and the same spreadsheet and Markdown safety as the leaderboard's export), or
the whole night as JSON: rules, entrants, heats and standings."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

from league.bracket_records import NightBracket
from league.bracket_rounds import bracket_rounds
from league.brackets import BYE
from league.nights import Entrant, Heat, Night, Standing
from league.race_types import race_type_of
from league.report import SCORE_TITLES, Column, markdown_escape, seconds, to_csv, to_markdown
from sim.physics.labels import PHYSICAL
from sim.race.rules import RankingMethod


def standings_json(standings: Sequence[Standing]) -> list[dict[str, Any]]:
    return [
        {
            "position": s.position,
            "racer": s.entry.display_name,
            "racer_name": s.entry.racer,
            "model": s.entry.model,
            "physical": s.entry.physics == PHYSICAL,
            "points": s.points,
            "score": s.entry.score,
            "best_lap": s.entry.best_lap,
            "laps": s.entry.valid_laps,
            "offtracks": s.entry.offtracks,
            "race_id": s.entry.record_id,
            "verification": s.entry.verification or None,  # league.trust.standing, if known
        }
        for s in standings
    ]


def standing_car(standing: Standing) -> str:
    """The car a night's standing names: a physical car's name (its board's key) marked
    physical, as the night's entrants are, so it never reads as a garage model's name."""
    model = standing.entry.model
    return f"{model} (physical)" if standing.entry.physics == PHYSICAL else model


def bracket_json(drawn: NightBracket, names: Mapping[str, str]) -> dict[str, Any]:
    """A night's bracket as it stands: its seeds (racers, best first), every match with
    its two sides (a racer, "bye", or null while not known), winner, race and how far the
    loser finished behind; its rounds as racers name them (league.bracket_rounds), the
    match to race next, and the final order once decided. `names`: entrant ids' racers."""
    winners = drawn.winners

    def side(entrant: str | None) -> str | None:
        if entrant is None:
            return None
        return "bye" if entrant == BYE else names.get(entrant, entrant)

    def margin(match_id: str) -> float | None:
        race = drawn.races.get(match_id)
        return race.places[-1].gap_seconds if race is not None else None

    order, upcoming = drawn.final_order(), drawn.next_match()
    return {
        "format": drawn.bracket.format.value,
        "rules": drawn.rules.to_dict(),
        "seeds": [names.get(seed, seed) for seed in drawn.bracket.seeds],
        "matches": [
            {
                "id": match.id,
                "bracket": match.bracket,
                "round": match.round,
                "a": side(drawn.sides(match)[0]),
                "b": side(drawn.sides(match)[1]),
                "winner": side(winners.get(match.id)),
                "race_id": drawn.races[match.id].id if match.id in drawn.races else None,
                "margin_seconds": margin(match.id),
            }
            for match in drawn.bracket.matches
        ],
        "rounds": [
            {
                "name": one.title,
                "bracket": one.part,
                "matches": [match.id for match in one.matches],
            }
            for one in bracket_rounds(drawn)
        ],
        "next_match": upcoming.id if upcoming is not None else None,
        "final_order": None if order is None else [side(entrant) for entrant in order],
    }


def night_json(
    night: Night,
    entrants: Sequence[Entrant],
    heats: Sequence[Heat],
    standings: Sequence[Standing],
    bracket: NightBracket | None = None,
) -> dict[str, Any]:
    """The whole night; `bracket` its knock-out, once drawn (null before). It is handed
    to others (a file, the web), so an entrant's bundle or model folder is named by its
    file name, never its path on the host's disk."""
    names = {entrant.id: entrant.display_name for entrant in entrants}
    return {
        "id": night.id,
        "name": night.name,
        "track": night.track_name,
        "track_hash": night.track_hash,
        "season_id": night.season_id,
        "closed": night.closed,
        "held_on": night.held_on,
        "race_type": race_type_of(night.rules),
        "rules": night.rules.to_dict(),
        "entrants": [
            {
                "id": e.id,
                "racer": e.display_name,
                "racer_name": e.racer,
                "model": e.model_shown,
            }
            for e in entrants
        ],
        "heats": [
            {
                "position": h.position,
                "racer": h.entrant.display_name,
                "model": h.entrant.model_shown,
                "race_id": h.race_id,
            }
            for h in heats
        ],
        "standings": standings_json(standings),
        "bracket": bracket_json(bracket, names) if bracket is not None else None,
    }


def standings_columns(night: Night) -> list[Column]:
    method = night.rules.ranking
    columns = [
        Column("position", lambda s: "-" if s.position is None else str(s.position), True),
        Column("racer", lambda s: s.entry.display_name),
        Column("car", standing_car),
    ]
    if method is not RankingMethod.BEST_LAP:
        columns.append(Column(SCORE_TITLES[method], lambda s: seconds(s.entry.score), True))
    return [
        *columns,
        Column("best lap", lambda s: seconds(s.entry.best_lap), numeric=True),
        Column("laps", lambda s: str(s.entry.valid_laps), numeric=True),
        Column("off-tracks", lambda s: str(s.entry.offtracks), numeric=True),
        Column("points", lambda s: str(s.points), numeric=True),
    ]


def night_export(
    night: Night,
    entrants: Sequence[Entrant],
    heats: Sequence[Heat],
    standings: Sequence[Standing],
    kind: str,
    *,
    bracket: NightBracket | None = None,
) -> str:
    """The night as `kind`: json (with its bracket), csv or markdown."""
    if kind == "json":
        document = night_json(night, entrants, heats, standings, bracket)
        return json.dumps(document, indent=2) + "\n"
    columns = standings_columns(night)
    if kind == "csv":
        return to_csv(columns, standings)
    state = "final standings" if night.closed else "standings so far"
    heading = f"# {markdown_escape(night.name)}: {state}\n\n"
    about = markdown_escape(f"{night.held_on}, {night.track_name}; {night.rules.describe()}.")
    return f"{heading}{about}\n\n{to_markdown(columns, standings)}"

"""A league night as the screens show it: the night, its running order, every heat's
best lap, the entrants not drawn yet, the standings, its bracket once drawn, and the
season's once it closes.
Read in one go, in a worker, for the Nights screen and the night's projector alike."""

from __future__ import annotations

from dataclasses import dataclass, field

from league.bracket_records import NightBracket, read_bracket
from league.nights import Entrant, Heat, Night, Standing, entrants, get_night, heats, standings
from league.seasons import SeasonStanding, get_season, season_standings
from league.store import League


@dataclass(frozen=True)
class NightState:
    night: Night
    heats: list[Heat]
    best_laps: dict[str, float | None]  # race id -> its best counting lap (corrections kept)
    undrawn: list[Entrant]  # entered, with no heat in the order yet
    standings: list[Standing]
    season_name: str | None
    season: list[SeasonStanding] | None  # once the night is closed and in a season
    bracket: NightBracket | None = None  # its knock-out, once drawn (league.bracket_nights)
    names: dict[str, str] = field(default_factory=dict)  # entrant id -> display name


def read_night(league: League, night_id: str) -> NightState:
    night = get_night(league, night_id)
    table = standings(league, night)
    season_name = None
    season = None
    if night.season_id is not None:
        found = get_season(league, night.season_id)
        season_name = found.name
        if night.closed:
            season = season_standings(league, found)
    # Every race's own best lap, not only the racer's best race of the night (the entries
    # cache keeps each race's figures with corrections applied).
    best_laps = {
        str(row["entry_id"]): row["best_lap"]
        for row in league.query(
            "SELECT entry_id, best_lap FROM entries WHERE night_id = ?", (night_id,)
        )
    }
    order = heats(league, night)
    in_order = {heat.entrant.id for heat in order}
    entered = entrants(league, night)
    undrawn = [entrant for entrant in entered if entrant.id not in in_order]
    names = {entrant.id: entrant.display_name for entrant in entered}
    bracket = read_bracket(league, night_id)
    return NightState(night, order, best_laps, undrawn, table, season_name, season, bracket, names)

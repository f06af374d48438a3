"""Seasons: a series of league nights whose closed results add up to season standings.

A night's standings give points by position from the season's points table (default
25-18-15-12-10-8-6-4-2-1, configurable per season, frozen in the season row). Season
standings order racers by points, then by countback (more wins, then more second places,
and so on), then by name: a total order, so every machine prints the same table.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

from league.bracket_records import bracket_places, with_bracket_places
from league.errors import LeagueError
from league.leaderboard import Filters, LeaderboardRow, grouped_rows, rank_groups
from league.racers import check_name
from league.store import League, now_iso

DEFAULT_POINTS: tuple[int, ...] = (25, 18, 15, 12, 10, 8, 6, 4, 2, 1)
MAX_POINTS_PLACES = 100


@dataclass(frozen=True)
class Season:
    id: str
    name: str
    points: tuple[int, ...]
    created_at: str


@dataclass(frozen=True)
class SeasonStanding:
    position: int
    racer: str
    display_name: str
    points: int
    nights: int  # closed nights the racer raced in
    finishes: tuple[int, ...]  # how many 1st, 2nd, ... places (as long as the points table)

    @property
    def wins(self) -> int:
        return self.finishes[0] if self.finishes else 0


def parse_points(text: str) -> tuple[int, ...]:
    """'25,18,15' -> (25, 18, 15): whole, non-negative, never more for a worse place."""
    try:
        points = tuple(int(part) for part in text.replace(" ", "").split(","))
    except ValueError:
        raise LeagueError(
            f"points {text!r} must be whole numbers separated by commas, like 25,18,15."
        ) from None
    return check_points(points)


def check_points(points: Sequence[int]) -> tuple[int, ...]:
    values = tuple(points)
    if (
        not values
        or len(values) > MAX_POINTS_PLACES
        or any(
            isinstance(p, bool) or not isinstance(p, int) or not 0 <= p <= 10_000 for p in values
        )
        or any(later > earlier for earlier, later in itertools.pairwise(values))
    ):
        raise LeagueError(
            f"a points table needs 1 to {MAX_POINTS_PLACES} whole numbers from 0 to 10000, "
            "never more for a worse place (like 25,18,15,12,10,8,6,4,2,1)."
        )
    return values


def new_season(league: League, name: str, points: Sequence[int] = DEFAULT_POINTS) -> Season:
    clean = check_name(name, "season name")
    table = check_points(points)
    with league.transaction():
        if league.query_one("SELECT 1 FROM seasons WHERE name = ?", (clean,)):
            raise LeagueError(f"there is already a season called {clean!r}; pick another name.")
        season_id = league.insert_record(
            "seasons", {"name": clean, "points": json.dumps(list(table)), "created_at": now_iso()}
        )
    return get_season(league, season_id)


def get_season(league: League, spec: str) -> Season:
    """A season by id or by name."""
    row = league.query_one(
        "SELECT * FROM seasons WHERE id = ? OR name = ?", (spec.strip().upper(), spec.strip())
    )
    if row is None:
        raise LeagueError(
            f"there is no season {spec!r}; create it with `racer-tui season new NAME`."
        )
    return Season(row["id"], row["name"], tuple(json.loads(row["points"])), row["created_at"])


def list_seasons(league: League) -> list[Season]:
    return [
        Season(row["id"], row["name"], tuple(json.loads(row["points"])), row["created_at"])
        for row in league.query("SELECT * FROM seasons ORDER BY id")
    ]


def closed_nights(league: League, season: Season) -> list[str]:
    rows = league.query(
        "SELECT n.id FROM nights n JOIN night_closures c ON c.night_id = n.id "
        "WHERE n.season_id = ? ORDER BY n.id",
        (season.id,),
    )
    return [row[0] for row in rows]


def night_results(
    league: League, night_ids: Sequence[str], local_models: Collection[str] = ()
) -> list[LeaderboardRow]:
    """Each racer's best race per night, ranked per night by the night's rules (which
    results count too: a night's `verification` rule; `local_models`, the garage's model
    hashes, make their races verifiable)."""
    if not night_ids:
        return []
    filters = Filters(night_ids=night_ids, local_models=frozenset(local_models))
    rows = grouped_rows(league, filters, None, group_by="night_id, racer")
    ranked = rank_groups(rows, lambda entry: entry.night_id, night_ids)
    # A bracket night's places are its bracket's, once decided: qualifying only seeded it.
    return with_bracket_places(ranked, bracket_places(league, night_ids))


def season_standings(league: League, season: Season) -> list[SeasonStanding]:
    """Points from every closed night of the season, best first."""
    places = len(season.points)
    totals: dict[str, int] = {}
    nights: dict[str, int] = {}
    finishes: dict[str, list[int]] = {}
    results = night_results(league, closed_nights(league, season))
    for row in results:
        totals.setdefault(row.racer, 0)
        nights[row.racer] = nights.get(row.racer, 0) + 1
        counts = finishes.setdefault(row.racer, [0] * places)
        if row.score is not None and row.rank <= places:
            totals[row.racer] += season.points[row.rank - 1]
            counts[row.rank - 1] += 1
    shown = {row.racer: row.display_name for row in results}
    order = sorted(
        totals,
        key=lambda racer: (
            -totals[racer],
            tuple(-count for count in finishes[racer]),
            racer.casefold(),
        ),
    )
    return [
        SeasonStanding(
            position=i,
            racer=racer,
            display_name=shown.get(racer, racer),
            points=totals[racer],
            nights=nights[racer],
            finishes=tuple(finishes[racer]),
        )
        for i, racer in enumerate(order, start=1)
    ]


def season_json(league: League, season: Season) -> dict[str, Any]:
    """The season as `racer-tui season show --json` writes it (and the web's night page)."""
    return {
        "id": season.id,
        "name": season.name,
        "points": list(season.points),
        "nights": len(closed_nights(league, season)),
        "standings": [
            {
                "position": s.position,
                "racer": s.display_name,
                "racer_name": s.racer,
                "points": s.points,
                "nights": s.nights,
                "wins": s.wins,
            }
            for s in season_standings(league, season)
        ],
    }

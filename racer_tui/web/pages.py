"""What the web pages and their JSON show, read from the league as the command line reads
it: the leaderboard's boards ranked by the one ranking the app and `racer-tui
leaderboard` use, its head-to-head board as `racer-tui leaderboard --race-type
head-to-head` gives it, and a night (its bracket too) as `racer-tui night show --json`
gives it. The JSON field names are those commands' own, so a league's site or bot reads
one format whichever it asks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from league.bracket_records import read_bracket
from league.errors import LeagueError
from league.head_to_head_board import HeadToHeadBoard, head_to_head_json, read_head_to_head_board
from league.leaderboard import (
    BY_CHOICES,
    Filters,
    LeaderboardRow,
    board_of,
    leaderboard,
    mark_verification,
    method_for,
    mixed_runtimes,
)
from league.night_report import night_json
from league.nights import Night, entrants, get_night, heats, list_nights, standings
from league.report import SCORE_TITLES, leaderboard_json
from league.seasons import get_season, season_json
from league.store import League
from league.tracks import track_names
from sim.race.rules import RankingMethod

DEFAULT_BY = "best"


@dataclass(frozen=True)
class Board:
    """One leaderboard: a track under one race type and one physics, ranked alone."""

    name: str  # as the leaderboard names it ("reinvent_base (DeepRacer)")
    track: str
    race_type: str
    physics: str
    rows: list[dict[str, Any]]  # leaderboard_json's rows, in rank order
    # What the board says when its races were driven under several policy runtimes
    # (league.leaderboard.mixed_runtimes); None when it has nothing to say.
    runtimes_note: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "board": self.name,
            "track": self.track,
            "race_type": self.race_type,
            "physics": self.physics,
            "runtimes_note": self.runtimes_note,
            "rows": self.rows,
        }


@dataclass(frozen=True)
class Leaderboard:
    ranking: RankingMethod
    by: str  # the `by` word that chose it: best, average or total
    boards: list[Board]
    # Head-to-head races rank no laps, so they are on no lap board: who beat whom instead.
    head_to_head: HeadToHeadBoard

    @property
    def ranking_words(self) -> str:
        return SCORE_TITLES[self.ranking]

    @property
    def score_column(self) -> bool:
        """Whether the score needs a column of its own: a best lap is one already."""
        return self.ranking is not RankingMethod.BEST_LAP

    def to_json(self) -> dict[str, Any]:
        return {
            "ranking": self.ranking.value,
            "by": self.by,
            "boards": [board.to_json() for board in self.boards],
            "head_to_head": head_to_head_json(self.head_to_head, None),
        }


def ranking_for(by: str | None) -> tuple[str, RankingMethod]:
    """The `by` word (default best lap) and its ranking; LeagueError names the choices."""
    word = by or DEFAULT_BY
    if word not in BY_CHOICES:
        raise LeagueError(f"by must be one of {', '.join(BY_CHOICES)}, not {word!r}.")
    return word, method_for(word)


def league_leaderboard(league: League, by: str | None, local_models: frozenset[str]) -> Leaderboard:
    """Every board of the league, each ranked by `by` (best lap unless it says otherwise),
    in the order the app lists them, and the head-to-head board of every head-to-head
    race; each row says how far it was verified here."""
    word, method = ranking_for(by)
    rows = leaderboard(league, Filters(local_models=local_models), method)
    mark_verification(league, rows, local_models)
    grouped: dict[tuple[str, str, str], list[LeaderboardRow]] = {}
    for row in rows:
        grouped.setdefault(board_of(row), []).append(row)
    tracks = track_names(league)
    boards = []
    for group in grouped.values():
        first = group[0]
        boards.append(
            Board(
                name=first.track_name,  # the board's name, as the leaderboard gives it
                track=tracks.get(first.track_hash, first.track_name),
                race_type=first.race_type,
                physics=first.physics,
                rows=leaderboard_json(group, method),
                runtimes_note=mixed_runtimes(group),
            )
        )
    return Leaderboard(
        method, word, boards, read_head_to_head_board(league, local_models=local_models)
    )


def shown_night(league: League, spec: str | None) -> Night | None:
    """The night `spec` names, or else the newest open night, or else the newest night;
    None when the league has none yet."""
    if spec:
        return get_night(league, spec)
    nights = list_nights(league)  # in id order: the newest last
    open_nights = [night for night in nights if not night.closed]
    if open_nights:
        return open_nights[-1]
    return nights[-1] if nights else None


def night_document(league: League, night: Night, local_models: frozenset[str]) -> dict[str, Any]:
    """The night as `racer-tui night show --json` writes it, with its rules in words."""
    ranked = standings(league, night, local_models=local_models)
    mark_verification(league, [standing.entry for standing in ranked], local_models)
    entered, bracket = entrants(league, night), read_bracket(league, night.id)
    document = night_json(night, entered, heats(league, night), ranked, bracket)
    document["rules_words"] = night.rules.describe()
    # Its season's points so far, as `season show --json` gives them (none: null).
    season = get_season(league, night.season_id) if night.season_id else None
    document["season"] = season_json(league, season) if season is not None else None
    return document

"""The leaderboard's filter bar (track, night, season, ranking method) and the query it
describes, shared by the League section and the projector so both rank the same way.

A query also names a race type (league.race_types): the boards shown are of one race type
at a time, the one asked for when the chosen track (night, season) has laps of it, else
the first that has (time trials first), so choosing a track never shows an empty board
while it has laps of another race type. The head-to-head board (league.head_to_head_board)
comes after the lap boards' race types when the track (night) has head-to-head races: it
ranks racers by wins, so the season and ranking-method filters give way on it
(`for_head_to_head`), each saying why.

`board_rows` and `filter_options` read the database: call them in a thread worker, with a
league opened in that thread (SQLite connections belong to the thread that opened them).
"""

from __future__ import annotations

from dataclasses import dataclass

from textual import events, on
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.message import Message
from textual.widgets import Select

from league.head_to_head_board import (
    NOT_FOR_HEAD_TO_HEAD,
    HeadToHeadBoard,
    read_head_to_head_board,
)
from league.head_to_heads import has_head_to_heads
from league.leaderboard import BY_CHOICES, Filters, LeaderboardRow, leaderboard
from league.nights import list_nights
from league.race_types import HEAD_TO_HEAD_BOARD, TIME_TRIAL, in_order
from league.seasons import list_seasons
from league.store import League
from league.tracks import track_names
from sim.race.rules import RankingMethod

BY_LABELS = {"best": "best lap", "average": "best average", "total": "total time"}
BY_OPTIONS = [(f"by {label}", by) for by, label in BY_LABELS.items()]


@dataclass(frozen=True)
class BoardQuery:
    """What the leaderboard shows: None means "every"."""

    track_hash: str | None = None
    night_id: str | None = None
    season_id: str | None = None
    by: str = "best"
    race_type: str = TIME_TRIAL  # whose boards: see board_view

    @property
    def method(self) -> RankingMethod:
        return BY_CHOICES.get(self.by, RankingMethod.BEST_LAP)


@dataclass(frozen=True)
class FilterOptions:
    """(label, value) pairs for each Select, read from the database."""

    tracks: list[tuple[str, str]]
    nights: list[tuple[str, str]]
    seasons: list[tuple[str, str]]


def filter_options(league: League) -> FilterOptions:
    tracks = sorted(track_names(league).items(), key=lambda item: item[1].casefold())
    nights = [
        (f"{night.name}{' (open)' if not night.closed else ''}", night.id)
        for night in reversed(list_nights(league))  # newest first
    ]
    seasons = [(season.name, season.id) for season in list_seasons(league)]
    return FilterOptions([(name, key) for key, name in tracks], nights, seasons)


@dataclass(frozen=True)
class BoardView:
    """What a query shows: the rows of one race type's boards, which race type that is,
    and every race type with laps under the query's other filters (in the league's order,
    then the head-to-head board when there are head-to-head races)."""

    rows: list[LeaderboardRow]
    race_type: str
    race_types: list[str]
    head_to_head: HeadToHeadBoard | None = None  # when race_type is HEAD_TO_HEAD_BOARD


def board_view(
    league: League, query: BoardQuery, local_models: frozenset[str] = frozenset()
) -> BoardView:
    """The ranked rows for `query` (a season means the races of its nights), of the query's
    race type when there are laps of it, else of the first race type that has some.
    `local_models` (the garage's model hashes) say which head-to-head races could be raced
    again here."""
    night_ids: list[str] | None = [query.night_id] if query.night_id else None
    if query.season_id is not None:
        in_season = [n.id for n in list_nights(league) if n.season_id == query.season_id]
        night_ids = in_season if night_ids is None else [n for n in night_ids if n in in_season]
    filters = Filters(track_hash=query.track_hash, night_ids=night_ids)
    rows = leaderboard(league, filters, query.method)  # every race type's: ranked per board
    present = in_order({row.race_type for row in rows})
    # Head-to-head races are on no season (a season is its nights' heats, time trials).
    if query.season_id is None and has_head_to_heads(
        league, track_hash=query.track_hash, night_id=query.night_id
    ):
        present.append(HEAD_TO_HEAD_BOARD)
    shown = query.race_type if query.race_type in present or not present else present[0]
    if shown == HEAD_TO_HEAD_BOARD:
        board = read_head_to_head_board(
            league,
            track_hash=query.track_hash,
            night_id=query.night_id,
            local_models=local_models,
        )
        return BoardView([], shown, present, board)
    if present != [shown]:
        rows = [row for row in rows if row.race_type == shown]
    return BoardView(rows, shown, present)


def board_rows(league: League, query: BoardQuery) -> list[LeaderboardRow]:
    """The ranked rows `board_view` shows for `query`."""
    return board_view(league, query).rows


def _value(select: Select[str]) -> str | None:
    value = select.value
    return None if value is Select.NULL else str(value)


# Below this width each filter is too narrow for its label inside a border.
COMPACT_BELOW_COLUMNS = 76


class BoardFilters(Horizontal):
    """Four Selects; any change posts `BoardFilters.Changed` with the new query."""

    DEFAULT_CSS = """
    BoardFilters { height: auto; }
    BoardFilters > Select { width: 1fr; }
    BoardFilters > #filter-by { max-width: 24; }
    /* A chosen value wider than its filter ends in an ellipsis on its one line: wrapped,
       "beginner-oval" read "beginner-ova" over "l", a row the board lost (the host walk). */
    BoardFilters SelectCurrent Static#label { text-wrap: nowrap; text-overflow: ellipsis; }
    """

    @dataclass
    class Changed(Message):
        query: BoardQuery

    def on_resize(self, event: events.Resize) -> None:
        # Four bordered selects in fewer columns wrap their labels to two lines each: a
        # filter row of four rows that the board, on a short terminal, needs more.
        compact = event.size.width < COMPACT_BELOW_COLUMNS
        for select in self.query(Select).results(Select):
            select.compact = compact

    def compose(self) -> ComposeResult:
        yield Select[str]([], prompt="every track", id="filter-track")
        yield Select[str]([], prompt="every night", id="filter-night")
        yield Select[str]([], prompt="every season", id="filter-season")
        yield Select[str](
            BY_OPTIONS,
            value="best",
            allow_blank=False,
            id="filter-by",
        )

    # The ranking method chosen for the lap boards, kept while the head-to-head board
    # shows "by wins" in its place (None: the lap boards are shown).
    _lap_boards_by: str | None = None

    @property
    def current(self) -> BoardQuery:
        return BoardQuery(
            track_hash=_value(self.query_one("#filter-track", Select)),
            night_id=_value(self.query_one("#filter-night", Select)),
            season_id=_value(self.query_one("#filter-season", Select)),
            by=self._lap_boards_by or _value(self.query_one("#filter-by", Select)) or "best",
        )

    def for_head_to_head(self, shown: bool) -> None:
        """Whether the head-to-head board is shown: it is ranked by wins and on no season,
        so those two filters are disabled, saying so ("by wins", "no seasons", and why in
        their tooltips), and come back as they were with the lap boards."""
        if shown == (self._lap_boards_by is not None):
            return
        season = self.query_one("#filter-season", Select)
        by = self.query_one("#filter-by", Select)
        with by.prevent(Select.Changed):
            if shown:
                self._lap_boards_by = _value(by) or "best"
                by.set_options([("by wins", "wins")])
                by.value = "wins"
            else:
                by.set_options(BY_OPTIONS)
                by.value, self._lap_boards_by = self._lap_boards_by or "best", None
        season.prompt = "no seasons" if shown else "every season"
        for select, why in (
            (season, NOT_FOR_HEAD_TO_HEAD["season"]),
            (by, NOT_FOR_HEAD_TO_HEAD["by"]),
        ):
            select.disabled = shown
            select.tooltip = f"{why[0].upper()}{why[1:]}." if shown else None

    def set_options(self, options: FilterOptions) -> None:
        """New choices, keeping each current choice that still exists."""
        for select_id, choices in (
            ("#filter-track", options.tracks),
            ("#filter-night", options.nights),
            ("#filter-season", options.seasons),
        ):
            select: Select[str] = self.query_one(select_id, Select)
            current = select.value
            with select.prevent(Select.Changed):
                select.set_options(choices)
                if current is not Select.NULL and current in {value for _, value in choices}:
                    select.value = current

    @on(Select.Changed)
    def _changed(self, event: Select.Changed) -> None:
        event.stop()
        self.post_message(self.Changed(self.current))

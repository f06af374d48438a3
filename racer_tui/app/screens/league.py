"""League: the leaderboard, sortable by every column, filtered by track, night and season,
with the highlighted entry's detail beside it, export, the projector and league nights.

Boards of one race type are shown at a time (time trials, object avoidance, head-to-bot
never share a board): when the chosen track has laps of more than one, a line says which
race type is shown and t switches to the next. After the lap boards comes the head-to-head
board when the league has head-to-head races: who beat whom, ranked by wins
(racer_tui.app.widgets.head_to_head_board), with a racer's record against each rival and
their races in the detail.

Every database read runs in a thread worker that opens its own connection and posts a
past-tense message; the formatters for the table cells and the exports are the league's
own (league.report), so the app, the CLI and the exported files agree.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Container, VerticalScroll
from textual.message import Message
from textual.widgets import DataTable, Static

from league.head_to_head_board import NOT_FOR_HEAD_TO_HEAD, HeadToHeadBoard, HeadToHeadRow
from league.leaderboard import (
    Column,
    LeaderboardRow,
    board_runtimes,
    mark_verification,
    several_boards,
    sort_rows,
)
from league.opening import open_league
from league.race_types import HEAD_TO_HEAD_BOARD, TIME_TRIAL, board_name, words
from league.report import (
    SCORE_TITLES,
    leaderboard_columns,
    leaderboard_json,
    to_csv,
    to_markdown,
)
from league.report import Column as ReportColumn
from racer_tui.app.league_watch import LEAGUE_POLL_SECONDS, LeagueWatch
from racer_tui.app.screens.base import RacerScreen, push_kept
from racer_tui.app.screens.dialogs import InputDialog
from racer_tui.app.screens.export_path import EXPORT_FORMATS, check_export_path, export_folder
from racer_tui.app.screens.nights import NightsScreen
from racer_tui.app.screens.projector import ProjectorScreen
from racer_tui.app.screens.races import replay_recorded_race
from racer_tui.app.screens.sync import SyncScreen
from racer_tui.app.widgets import head_to_head_board as head_to_head_view
from racer_tui.app.widgets.board_filters import (
    BoardFilters,
    BoardQuery,
    BoardView,
    FilterOptions,
    board_view,
    filter_options,
)
from racer_tui.app.widgets.entry_detail import EntryDetail, describe_entry
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.sync_status import SyncStatusLine
from racer_tui.app.widgets.table_fill import (
    Col,
    FittedTable,
    column_index,
    fill_table,
    shown_columns,
)
from sim.foundation.atomic import write_text_atomic
from sim.foundation.plain_names import look_alike_key
from sim.foundation.plural import counted
from sim.training.drivers import DriversByHash

NARROW = 120  # below this many columns the detail panel goes under the table
# Table titles (league.report's) -> the sort keys league.leaderboard knows.
SORT_BY_TITLE: dict[str, Column] = {
    "rank": Column.RANK,
    "racer": Column.RACER,
    "model": Column.MODEL,
    "track": Column.TRACK,
    "best lap": Column.BEST,
    "average": Column.AVERAGE,
    "laps": Column.LAPS,
    "off-tracks": Column.OFFTRACKS,
    "submitted": Column.SUBMITTED,
    "verification": Column.VERIFICATION,
    **{title: Column.SCORE for title in SCORE_TITLES.values()},
}
# How each column gives way in a narrow terminal (see table_fill.Col): the submission date
# first, then the average, off-tracks and laps (the entry's detail shows them). The board
# (the track column names it, "(physical)" and all), the model and the racer lose the end
# of their names but are never dropped: two rank 1s on one screen must say which board each
# leads. Rank, score and best lap always stay.
GIVE_WAY: dict[str, Col] = {
    "submitted": Col("", keep=1),
    "average": Col("", keep=2),
    "off-tracks": Col("", keep=3),
    "laps": Col("", keep=4),
    # Whether a result was replayed here outlasts the counts: the entry's detail says it too.
    "verification": Col("", keep=5),
    "racer": Col("", keep=6, shrink_to=10, collapses=False),
    "model": Col("", keep=7, shrink_to=8, collapses=False, cuts_middle=True),
    "track": Col("", keep=8, shrink_to=8, collapses=False, keeps_tail=True),
}


def export_text(
    rows: list[LeaderboardRow], query: BoardQuery, kind: str, show_track: bool | None = None
) -> str:
    """The file contents, through the same formatters as `racer-tui leaderboard`;
    `show_track` as the table shows it (the dialog promises "the table as shown"), by
    default only when the rows span several boards."""
    if kind == "json":
        return json.dumps(leaderboard_json(rows, query.method), indent=2) + "\n"
    track = several_boards(rows) if show_track is None else show_track
    columns = leaderboard_columns(
        query.method, show_track=track, iso_times=kind == "csv", verification=True
    )
    return to_csv(columns, rows) if kind == "csv" else to_markdown(columns, rows)


# --- messages from the workers --------------------------------------------------------------


@dataclass
class BoardLoaded(Message):
    view: BoardView
    options: FilterOptions
    query: BoardQuery  # as shown: its race type is the view's
    generation: int  # a slower, older read must not win


def race_type_line(view: BoardView) -> Text:
    """Which race type's boards are shown, and what t switches to ("" when every lap is
    a time trial, as in a league that races nothing else)."""
    if view.race_types in ([], [TIME_TRIAL]):
        return Text()
    if view.race_type == HEAD_TO_HEAD_BOARD:  # one board, ranked by wins: why "by wins"
        text = Text.assemble(("Head-to-head, ranked by wins", "bold"))
    else:
        text = Text.assemble((f"{words(view.race_type).capitalize()} boards", "bold"))
    others = [kind for kind in view.race_types if kind != view.race_type]
    if not others:
        text.append("  (no other race type has laps here)", style="dim")
        return text
    after = view.race_types[(view.race_types.index(view.race_type) + 1) % len(view.race_types)]
    text.append(f"  ·  t switches to {words(after)}", style="dim")
    if len(others) > 1:
        text.append(f" ({len(view.race_types)} race types here)", style="dim")
    return text


def runtimes_line(rows: list[LeaderboardRow]) -> Text:
    """Says so when the shown races were driven under more than one policy runtime
    (`board_runtimes`); each row's detail names its own. Empty otherwise."""
    runtimes = board_runtimes(rows)
    if len(runtimes) < 2:
        return Text()
    # Short enough for one line at 60 columns; a row's detail names its own runtime.
    return Text(
        f"{len(runtimes)} policy runtimes here: their numerics differ",
        style="yellow",
    )


@dataclass
class EntryDescribed(Message):
    record_id: str
    text: Text


@dataclass
class BoardExported(Message):
    path: Path
    count: int


@dataclass(frozen=True)
class SortOrder:
    column: Column | None = None  # None: the league's ranking order
    reverse: bool = False


class LeagueScreen(RacerScreen[None]):
    """The leaderboard section. `db_path` None is the league in the data folder."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "sort_next", "Sort", tooltip="Sort by the next column (or click a header)"),
        Binding("r", "reverse", "Reverse", tooltip="Reverse the sort order"),
        Binding(
            "t",
            "race_type",
            "Race type",
            tooltip="The boards of another race type (time trial, object avoidance, "
            "head-to-bot, head-to-head) on the chosen track",
        ),
        Binding("x", "export", "Export", tooltip="Write the table as CSV, JSON or Markdown"),
        Binding("n", "nights", "Nights", tooltip="Run a league night: entrants, heats, standings"),
        Binding("p", "projector", "Projector", tooltip="Full-screen leaderboard in large type"),
        Binding("y", "sync", "Sync", tooltip="The shared store: sync, conflicts, quarantine"),
        Binding("ctrl+r", "reload", "Reload", tooltip="Read the league again", show=False),
        Binding("v", "replay_entry", "Replay", tooltip="Replay the entry's race", show=False),
    ]
    AUTO_FOCUS = "#board"  # the keys (s, r, arrows) act on the table from the start
    DEFAULT_CSS = """
    LeagueScreen #board-race-type { height: 1; padding: 0 1; }
    LeagueScreen #board-race-type.-hidden { display: none; }
    LeagueScreen #league-body { height: 1fr; layout: horizontal; }
    LeagueScreen #board { width: 3fr; height: 1fr; }
    LeagueScreen #entry-scroll { width: 2fr; min-width: 36; border-left: vkey $panel-lighten-2; }
    LeagueScreen.-narrow #league-body { layout: vertical; }
    LeagueScreen.-narrow #board { width: 100%; height: 1fr; }
    LeagueScreen.-narrow #entry-scroll {
        width: 100%; height: 1fr; max-height: 45%; border-left: none;
        border-top: hkey $panel-lighten-2;
    }
    """

    def __init__(self, *, db_path: Path | None = None) -> None:
        super().__init__()
        self.db_path = db_path
        self.rows: list[LeaderboardRow] = []  # as shown (sorted)
        self.ranked: list[LeaderboardRow] = []  # in the league's order
        self.titles: list[str] = []
        self.order = SortOrder()
        self.shown_query = BoardQuery()
        self.race_type = TIME_TRIAL  # the host's choice; shown when the track has laps of it
        self.race_types: list[str] = []  # with laps under the filters: what t cycles through
        # The head-to-head board when it is shown (then `rows` and `ranked` are empty).
        self.head_to_head: HeadToHeadBoard | None = None
        self.night_names: dict[str, str] = {}  # the league's nights by id
        self.track_names: dict[str, str] = {}  # the league's tracks by hash
        self.loaded = False
        self._generation = 0
        self._garage_hashes: frozenset[str] | None = None  # see _models_here
        self.league_watch = LeagueWatch(db_path)  # writes made elsewhere (the command line)

    def compose(self) -> ComposeResult:
        yield SectionHeader("league")
        yield BoardFilters(id="board-filters")
        yield Static("", id="board-race-type", classes="-hidden")
        with Container(id="league-body"):
            yield FittedTable(id="board", cursor_type="row", zebra_stripes=True)
            with VerticalScroll(id="entry-scroll"):
                yield EntryDetail(id="entry-detail")
        yield SyncStatusLine(id="sync-status")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.reload()
        self.query_one(SyncStatusLine).read(self.db_path)
        self.set_interval(LEAGUE_POLL_SECONDS, self._look_for_changes)

    def _look_for_changes(self) -> None:
        """Read the board again when another process wrote to the league (a submission from
        the command line, a sync, a night's heat): only while the board is shown."""
        if self.loaded and self.is_current and self.league_watch.changed():
            self.reload()
            self.query_one(SyncStatusLine).read(self.db_path)

    @property
    def ready_for_keys(self) -> bool:
        """The app holds keys typed before the list has landed (racer_tui.app.application)."""
        return self.loaded

    def on_resize(self) -> None:
        self.set_class(self.size.width < NARROW, "-narrow")

    def on_screen_resume(self) -> None:
        if self.loaded:  # a night may have run heats since, or a sync pulled results
            self._garage_hashes = None  # and a model may have been trained or imported
            self.reload()
            self.query_one(SyncStatusLine).read(self.db_path)

    # --- loading -------------------------------------------------------------------------

    def reload(self) -> None:
        self.league_watch.reading()
        self._generation += 1
        query = replace(self.query_one(BoardFilters).current, race_type=self.race_type)
        self._load(query, self._generation)

    def action_reload(self) -> None:
        self._garage_hashes = None  # models trained or imported since count
        self.reload()
        self.query_one(SyncStatusLine).read(self.db_path)

    @on(BoardFilters.Changed)
    def _filters_changed(self) -> None:
        self.reload()

    @work(thread=True, exclusive=True, group="league-board", exit_on_error=False)
    def _load(self, query: BoardQuery, generation: int) -> None:

        with open_league(self.db_path) as league:
            view = board_view(league, query, self._models_here())
            mark_verification(league, view.rows, self._models_here())
            options = filter_options(league)
        if view.head_to_head is not None:
            # Racers' names are told apart in the table by how they look (table_fill):
            # the confusables table loads here, not in the table's first layout.
            look_alike_key("")
        shown = replace(query, race_type=view.race_type)
        self.post_message(BoardLoaded(view, options, shown, generation))

    def _models_here(self) -> frozenset[str]:
        """The garage's model hashes (their results are verifiable here), hashed once per
        visit in the loading worker: hashing every model is too slow for each reload."""
        if self._garage_hashes is None:
            self._garage_hashes = DriversByHash().models_here()
        return self._garage_hashes

    def on_board_loaded(self, message: BoardLoaded) -> None:
        if message.generation != self._generation:
            return
        self.loaded = True
        self.query_one(BoardFilters).set_options(message.options)
        self.ranked = message.view.rows
        kept = self.highlighted_racer  # read before the board it is on goes
        self.head_to_head = message.view.head_to_head
        self.shown_query = message.query
        self.race_types = message.view.race_types
        self.track_names = {track_hash: name for name, track_hash in message.options.tracks}
        self.night_names = {night_id: name for name, night_id in message.options.nights}
        self.query_one(BoardFilters).for_head_to_head(self.head_to_head is not None)
        parts = [
            part for part in (race_type_line(message.view), runtimes_line(self.ranked)) if part
        ]
        line = Text("\n").join(parts)
        label = self.query_one("#board-race-type", Static)
        label.update(line)
        label.set_class(not line.plain, "-hidden")
        self.refresh_bindings()  # t shows only when there is another race type to show
        if self.head_to_head is not None:
            self._show_head_to_head(self.head_to_head, kept.racer if kept else None)
        else:
            self._show()

    def _columns(self) -> list[ReportColumn]:
        query = self.shown_query
        # With a track chosen, still a track column when its laps of other physics than
        # today's are on boards of their own (the column names each board).
        show_track = query.track_hash is None or several_boards(self.ranked)
        columns = leaderboard_columns(query.method, show_track=show_track, verification=True)
        if query.race_type == TIME_TRIAL:
            return columns
        # One race type's boards: the line above the table names it, so the track column
        # keeps its room for the track (and the model its place at 80 columns).
        return [
            ReportColumn(column.title, self._track_cell, column.numeric)
            if column.title == "track"
            else column
            for column in columns
        ]

    def _track_cell(self, row: LeaderboardRow) -> str:
        track = self.track_names.get(row.track_hash)
        return row.track_name if track is None else board_name(track, row.physics, TIME_TRIAL)

    def _show(self) -> None:
        table = self.query_one("#board", DataTable)
        selected = self.highlighted
        order = self.order
        columns = self._columns()
        self.titles = [column.title for column in columns]
        if order.column is not None and order.column not in {SORT_BY_TITLE[t] for t in self.titles}:
            self.order = order = SortOrder()  # e.g. the track column left with a track filter
        if order.column is None:
            self.rows = list(reversed(self.ranked)) if order.reverse else list(self.ranked)
        else:
            self.rows = sort_rows(self.ranked, order.column.value, reverse=order.reverse)
        labels = []
        for column in columns:
            sorted_here = SORT_BY_TITLE[column.title] == (order.column or Column.RANK)
            arrow = (" ▼" if order.reverse else " ▲") if sorted_here else ""
            labels.append(replace(GIVE_WAY.get(column.title, Col("")), label=column.title + arrow))
        cells = [
            [
                Text(column.cell(row), justify="right" if column.numeric else "left")
                for column in columns
            ]
            for row in self.rows
        ]
        fill_table(table, labels, cells)
        count = len(self.rows)
        self.query_one(SectionHeader).set_context(
            f"{count} entr{'ies' if count != 1 else 'y'}" if count else ""
        )
        detail = self.query_one(EntryDetail)
        if not self.rows:
            detail.show_message(
                "No results here yet. Race a model in Races (3) and press u to submit it, "
                "or u in the Garage for a model's evaluation; a host runs a league night "
                "with n."
            )
            return
        ids = [row.record_id for row in self.rows]
        index = ids.index(selected.record_id) if selected and selected.record_id in ids else 0
        table.move_cursor(row=index)
        self._describe(self.rows[index])

    def _show_head_to_head(self, board: HeadToHeadBoard, kept: str | None) -> None:
        """The head-to-head board, the cursor on racer `kept` if they are still on it."""
        table = self.query_one("#board", DataTable)
        self.rows, self.titles = [], []
        columns, cells = head_to_head_view.board_table(board)
        fill_table(table, columns, cells)
        count = len(board.rows)
        self.query_one(SectionHeader).set_context(counted(count, "racer") if count else "")
        if not board.rows:
            self.query_one(EntryDetail).show_message(head_to_head_view.EMPTY)
            return
        racers = [row.racer for row in board.rows]
        index = racers.index(kept) if kept in racers else 0
        table.move_cursor(row=index)
        self._describe_racer(board, board.rows[index])

    @property
    def highlighted(self) -> LeaderboardRow | None:
        table = self.query_one("#board", DataTable)
        if 0 <= table.cursor_row < len(self.rows):
            return self.rows[table.cursor_row]
        return None

    @property
    def highlighted_racer(self) -> HeadToHeadRow | None:
        """The head-to-head board's highlighted row (None on a lap board)."""
        table = self.query_one("#board", DataTable)
        board = self.head_to_head
        if board is not None and 0 <= table.cursor_row < len(board.rows):
            return board.rows[table.cursor_row]
        return None

    @on(DataTable.RowHighlighted, "#board")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        board = self.head_to_head
        if board is not None:
            if 0 <= event.cursor_row < len(board.rows):
                self._describe_racer(board, board.rows[event.cursor_row])
        elif 0 <= event.cursor_row < len(self.rows):
            self._describe(self.rows[event.cursor_row])

    def _describe_racer(self, board: HeadToHeadBoard, row: HeadToHeadRow) -> None:
        """From the board as read (every race of it is there): no read of its own."""
        text = head_to_head_view.describe_racer(board, row, self.track_names, self.night_names)
        self.query_one(EntryDetail).update(text)

    @work(thread=True, exclusive=True, group="league-detail", exit_on_error=False)
    def _describe(self, row: LeaderboardRow) -> None:
        with open_league(self.db_path) as league:
            text = describe_entry(league, row)
        self.post_message(EntryDescribed(row.record_id, text))

    def on_entry_described(self, message: EntryDescribed) -> None:
        row = self.highlighted
        if row is not None and row.record_id == message.record_id:
            self.query_one(EntryDetail).update(message.text)

    # --- sorting -------------------------------------------------------------------------

    def sort_by(self, column: Column | None, *, reverse: bool = False) -> None:
        self.order = SortOrder(column, reverse)
        self._show()

    def _ranked_by_wins(self) -> bool:
        """On the head-to-head board, say why it does not sort (True) instead: from its
        keys, a header click and the command palette alike."""
        if self.head_to_head is None:
            return False
        why = NOT_FOR_HEAD_TO_HEAD["sort"]
        self.notify(f"{why[0].upper()}{why[1:]}: s and r sort the lap boards.")
        return True

    def action_sort_next(self) -> None:
        if self._ranked_by_wins() or not self.titles:
            return
        # Only the columns the racer can see: a collapsed one would sort out of sight.
        shown = shown_columns(self.query_one("#board", DataTable))
        keys = [SORT_BY_TITLE[title] for i, title in enumerate(self.titles) if i in shown]
        current = self.order.column or Column.RANK
        position = keys.index(current) if current in keys else 0
        self.sort_by(keys[(position + 1) % len(keys)])

    def action_reverse(self) -> None:
        if not self._ranked_by_wins():
            self.sort_by(self.order.column, reverse=not self.order.reverse)

    @on(DataTable.HeaderSelected, "#board")
    def _header_clicked(self, event: DataTable.HeaderSelected) -> None:
        index = column_index(event)
        if self._ranked_by_wins() or not 0 <= index < len(self.titles):
            return
        column = SORT_BY_TITLE[self.titles[index]]
        same = column == (self.order.column or Column.RANK)
        self.sort_by(column, reverse=not self.order.reverse if same else False)

    # --- race types ----------------------------------------------------------------------

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "race_type":
            return len(self.race_types) > 1
        return True

    def action_race_type(self) -> None:
        """The boards of the next race type with laps under the filters."""
        kinds = self.race_types
        if len(kinds) < 2:
            return
        shown = self.shown_query.race_type
        self.race_type = (
            kinds[(kinds.index(shown) + 1) % len(kinds)] if shown in kinds else kinds[0]
        )
        self.reload()

    # --- export, projector, nights -------------------------------------------------------

    def action_export(self) -> None:
        board = self.head_to_head
        if not (board.rows if board is not None else self.rows):
            self.notify("There is nothing to export: the leaderboard is empty.", severity="warning")
            return
        name = "head-to-head.csv" if board is not None else "leaderboard.csv"
        dialog = InputDialog(
            "Export the leaderboard",
            "The table as shown (filters and order). The file name's ending chooses the "
            "format: .csv, .json or .md (Markdown).",
            value=str(export_folder() / name),
            confirm_label="Export",
            check=check_export_path,
            paths=True,
        )
        self.app.push_screen(dialog, self._export_to)

    def _export_to(self, path: str | None) -> None:
        if path is not None:
            target = Path(path).expanduser()
            kind = EXPORT_FORMATS[target.suffix.lower()]
            board = self.head_to_head
            if board is not None:
                track = self.track_names.get(self.shown_query.track_hash or "")
                text = partial(head_to_head_view.export_text, board, track, kind)
                self._export(target, text, len(board.rows))
                return
            show_track = "track" in self.titles
            rows = list(self.rows)
            self._export(
                target, partial(export_text, rows, self.shown_query, kind, show_track), len(rows)
            )

    @work(thread=True, group="league-export", exit_on_error=False)
    def _export(self, path: Path, text: Callable[[], str], count: int) -> None:
        write_text_atomic(path, text())
        self.post_message(BoardExported(path, count))

    def on_board_exported(self, message: BoardExported) -> None:
        self.notify(
            f"Wrote {counted(message.count, 'row')} to {message.path}.", timeout=10, markup=False
        )

    def action_projector(self) -> None:
        if self.head_to_head is not None:
            self.notify(
                "The projector shows lap boards, not the head-to-head board yet.",
                severity="warning",
            )
            return
        self.app.push_screen(ProjectorScreen(self.shown_query, db_path=self.db_path))

    def action_nights(self) -> None:
        self.app.push_screen(NightsScreen(db_path=self.db_path))

    def action_sync(self) -> None:
        push_kept(self.app, f"sync:{self.db_path or ''}", partial(SyncScreen, db_path=self.db_path))

    def action_replay_entry(self) -> None:
        if self.head_to_head is not None:
            self.notify(
                "A recorded head-to-head race is not replayed in the app yet; "
                "racer-tui sync verify races it again.",
                severity="warning",
            )
            return
        row = self.highlighted
        if row is None or row.kind != "race":
            self.notify(
                "Only a race can be replayed; this entry is a submission (its evaluation has "
                "no trace).",
                severity="warning",
            )
            return
        replay_recorded_race(self, row.record_id, self.db_path)

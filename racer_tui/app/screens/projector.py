"""Projector mode: the leaderboard in large type for the room's big screen.

The leader's time in Digits, then big, spaced rows. A thread worker polls the database
every few seconds, so results recorded by the host's heats (or synced from other
machines) appear without a key press. A kiosk (`racer_tui.app.screens.kiosk`): q asks, then
leaves; no other screen opens from it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from rich import box
from rich.table import Table
from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Digits, Static

from league.leaderboard import LeaderboardRow, board_of, several_boards
from league.opening import open_league
from league.report import SCORE_TITLES
from racer_tui.app.screens.kiosk import LEAVE_HINT, KioskScreen, kiosk_bindings
from racer_tui.app.widgets.board_filters import BoardQuery, board_rows
from racer_tui.text.clocks import clock_text

POLL_SECONDS = 3.0
MAX_ROWS = 20  # a projector shows the top of the table; the rest would not be readable


@dataclass
class ProjectorLoaded(Message):
    rows: list[LeaderboardRow]
    title: str


NARROW = 70  # below this many columns the gap goes: the names need the room


def projector_table(
    rows: Sequence[LeaderboardRow], show_track: bool, narrow: bool = False
) -> Table:
    """Big rows: one blank line between racers, bold names, times right-aligned; no gap
    column when `narrow`."""
    table = Table(
        box=box.SIMPLE_HEAD, expand=True, padding=(0, 1 if narrow else 2), show_edge=False
    )
    table.add_column("#", justify="right", style="bold", width=3)
    table.add_column("racer", ratio=3, no_wrap=True, overflow="ellipsis")
    if show_track:
        # Wrapped at its spaces, never cut: "reinvent_base (physical)" cut to "reinven…" made
        # a physical car's board look like the simulated one, with two unexplained firsts.
        table.add_column("track", overflow="fold", max_width=16)
    table.add_column("time", justify="right", width=9)
    if not narrow:
        table.add_column("gap", justify="right", width=8)
    table.add_column("laps", justify="right", width=4)
    leaders: dict[tuple[str, str, str], float | None] = {}
    for row in rows:  # ranked board by board: the first row of a board leads it
        leaders.setdefault(board_of(row), row.score)
    for index, row in enumerate(rows):
        leader = leaders[board_of(row)]
        gap = (
            ""
            if row.score is None or leader is None or row.rank == 1
            else f"+{row.score - leader:.3f}"
        )
        cells: list[Text] = [
            Text(str(row.rank)),
            Text(row.display_name, style="bold"),  # plain text, never markup
        ]
        if show_track:
            cells.append(Text(row.track_name))
        cells += [
            Text(clock_text(row.score) if row.score is not None else "-", style="bold"),
            *([] if narrow else [Text(gap, style="dim")]),
            Text(str(row.valid_laps)),
        ]
        table.add_row(*cells, style="on grey15" if index % 2 else "", end_section=False)
        table.add_row()  # the spacing that makes rows readable from the back of the room
    return table


class ProjectorScreen(KioskScreen):
    """Full-screen leaderboard for `query`; `db_path` None is the default league."""

    BINDINGS: ClassVar[list[BindingType]] = kiosk_bindings(
        Binding("ctrl+r", "refresh_now", "Refresh", show=False),
    )
    DEFAULT_CSS = """
    ProjectorScreen { background: $background; }
    ProjectorScreen #projector-top { height: auto; padding: 1 2 0 2; }
    ProjectorScreen #projector-title-box { width: 1fr; height: auto; }
    ProjectorScreen #projector-title { width: 1fr; text-style: bold; color: $accent; }
    ProjectorScreen #projector-leader { width: auto; height: auto; }
    ProjectorScreen #projector-leader-name {
        width: 1fr; padding: 1 2 0 0; text-style: bold;
        text-wrap: nowrap; text-overflow: ellipsis;  /* a long name never runs under the clock */
    }
    ProjectorScreen #projector-rows { height: 1fr; padding: 0 2; }
    ProjectorScreen #projector-hint { height: 1; color: $text-muted; padding: 0 2; }
    """

    def __init__(self, query: BoardQuery, *, db_path: Path | None = None, title: str = "") -> None:
        super().__init__()
        self.board_query = query
        self.db_path = db_path
        self.title_text = title
        self.rows: list[LeaderboardRow] = []
        self.polls = 0

    def compose(self) -> ComposeResult:
        with Horizontal(id="projector-top"):
            with Vertical(id="projector-title-box"):
                yield Static(Text(self.title_text or "Leaderboard"), id="projector-title")
                yield Static("", id="projector-leader-name")
            yield Digits("-:--.---", id="projector-leader")
        yield Static("", id="projector-rows")
        yield Static(f"{LEAVE_HINT} · refreshes every few seconds", id="projector-hint")

    def on_mount(self) -> None:
        self.action_refresh_now()
        self.set_interval(POLL_SECONDS, self.action_refresh_now)

    def action_refresh_now(self) -> None:
        self._poll()

    @work(thread=True, exclusive=True, group="projector", exit_on_error=False)
    def _poll(self) -> None:
        with open_league(self.db_path) as league:
            rows = board_rows(league, self.board_query)
        tracks = sorted({row.track_name for row in rows})
        where = f" · {tracks[0]}" if len(tracks) == 1 else ""
        by = SCORE_TITLES[self.board_query.method]
        title = f"{self.title_text or 'Leaderboard'}{where} · by {by}"
        self.post_message(ProjectorLoaded(rows[:MAX_ROWS], title))

    def on_projector_loaded(self, message: ProjectorLoaded) -> None:
        self.polls += 1
        self.rows = message.rows
        self.query_one("#projector-title", Static).update(Text(message.title))
        leader = message.rows[0] if message.rows else None
        digits = self.query_one("#projector-leader", Digits)
        name = self.query_one("#projector-leader-name", Static)
        if leader is not None and leader.score is not None:
            digits.update(clock_text(leader.score))
            name.update(Text(f"Leader: {leader.display_name}"))
        else:
            digits.update("-:--.---")
            name.update(Text("No results yet" if not message.rows else "No valid lap yet"))
        show_track = several_boards(message.rows)
        rows = self.query_one("#projector-rows", Static)
        narrow = 0 < rows.size.width < NARROW
        rows.update(projector_table(message.rows, show_track, narrow))

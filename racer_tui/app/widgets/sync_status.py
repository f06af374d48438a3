"""One line about the shared store, under the leaderboard: where the league syncs, when it
last did and what moved, and what waits (to push, conflicts, quarantined).

The figures sit at the right; a long store URL is cut with an ellipsis instead (the Sync
screen shows it whole). Below COMPACT_BELOW columns the figures say only what matters (no
zero conflicts or quarantined, no arrows), so the URL keeps room to be recognised. The
figures come from league.sync.status.
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.message import Message
from textual.widgets import Static

from league.errors import LeagueError
from league.opening import open_league
from league.sync.status import SyncOverview, sync_overview

NO_STORE = "No shared store: press y to set one up"
COMPACT_BELOW = 100  # columns


def local_time(iso: str, *, now: datetime | None = None) -> str:
    """A stored UTC time in this machine's time zone: "14:05" today, else "2025-03-01 14:05"."""
    try:
        moment = datetime.fromisoformat(iso).astimezone()
    except ValueError:
        return iso
    today = (now or datetime.now().astimezone()).date()
    return moment.strftime("%H:%M" if moment.date() == today else "%Y-%m-%d %H:%M")


def store_text(overview: SyncOverview) -> Text:
    if overview.store is None:
        return Text(NO_STORE, style="italic")
    return Text.assemble(("⇅ ", "bold"), overview.store)  # a URL: plain text


def _figure(count: int, label: str, warn: bool) -> Text:
    return Text(f"{count} {label}", style="bold yellow" if warn and count else "")


def failed_text(overview: SyncOverview) -> list[Text]:
    """ "sync failed 14:10" when the last sync with the store failed (the Sync screen says
    why); nothing otherwise."""
    if overview.failure is None:
        return []
    return [Text(f"sync failed {local_time(overview.failure.at)}", style="bold yellow")]


def counts_text(overview: SyncOverview, *, compact: bool = False) -> Text:
    """When it last synced and what moved, then what waits; "" without a store. `compact`
    leaves out what moved and the warnings that are zero."""
    if overview.store is None:
        return Text("")
    last = overview.last_run
    if last is None:
        when = Text("never synced", style="dim")
    elif compact:
        when = Text(f"synced {local_time(last.finished_at)}", style="dim")
    else:
        arrows = [
            f"{arrow}{count}"
            for arrow, count in (("↑", overview.moved("push")), ("↓", overview.moved("pull")))
            if count is not None
        ]
        when = Text(f"synced {local_time(last.finished_at)} ({' '.join(arrows)})", style="dim")
    parts = [*failed_text(overview), when, _figure(overview.to_push or 0, "to push", warn=False)]
    if overview.conflicts or not compact:
        parts.append(
            _figure(overview.conflicts, "conflict" + "s" * (overview.conflicts != 1), warn=True)
        )
    if overview.quarantined or not compact:
        parts.append(_figure(overview.quarantined, "quarantined", warn=True))
    return Text(" · ").join(parts)


@dataclass
class SyncOverviewRead(Message):
    overview: SyncOverview | None
    problem: str = ""


class SyncStatusLine(Horizontal):
    """Reads its figures in a thread worker (`read`); a click runs the screen's `sync`
    action (the League screen opens the Sync screen)."""

    DEFAULT_CSS = """
    SyncStatusLine { height: 1; background: $panel; color: $text-muted; }
    SyncStatusLine > #sync-store {
        width: 1fr; padding: 0 1; text-wrap: nowrap; text-overflow: ellipsis;
    }
    SyncStatusLine > #sync-counts { width: auto; padding: 0 1; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.overview: SyncOverview | None = None

    def compose(self) -> ComposeResult:
        yield Static(Text("Shared store: reading…", style="dim"), id="sync-store")
        yield Static("", id="sync-counts")

    @work(thread=True, exclusive=True, group="sync-status-line", exit_on_error=False)
    def read(self, db_path: Path | None) -> None:
        """Read the league at `db_path` (None: the data folder's) and show its figures."""
        try:
            with open_league(db_path) as league:
                overview = sync_overview(league)
        except (OSError, sqlite3.Error, LeagueError) as error:
            # The leaderboard's own read reports the problem; the line just says so.
            self.post_message(SyncOverviewRead(None, f"Shared store: status unreadable ({error})"))
            return
        self.post_message(SyncOverviewRead(overview))

    def on_sync_overview_read(self, message: SyncOverviewRead) -> None:
        message.stop()
        if message.overview is None:
            self.query_one("#sync-store", Static).update(Text(message.problem, style="dim"))
            self.query_one("#sync-counts", Static).update("")
        else:
            self.show(message.overview)

    def show(self, overview: SyncOverview) -> None:
        self.overview = overview
        self.query_one("#sync-store", Static).update(store_text(overview))
        compact = self.size.width < COMPACT_BELOW
        self.query_one("#sync-counts", Static).update(counts_text(overview, compact=compact))

    def on_resize(self) -> None:
        if self.overview is not None:
            self.show(self.overview)

    async def on_click(self) -> None:
        await self.run_action("screen.sync")

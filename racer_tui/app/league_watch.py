"""Noticing that another process wrote to the league, so a screen showing it reads it again.

A host keeps a league screen open while `racer-tui night ...`, `racer-tui submit` or a sync
writes from another terminal: the screen must show what the league holds, not what it held
when it was last read. A stat of the database and its log every couple of seconds is cheap
enough for any screen; a query would not be.
"""

from __future__ import annotations

from pathlib import Path

from league.opening import FileStamp, league_stamp

# How often a screen that shows the league looks for writes made elsewhere: often enough
# that a host sees a command's change land as they turn back to the screen.
LEAGUE_POLL_SECONDS = 2.0


class LeagueWatch:
    """The league's files as last read by one screen."""

    def __init__(self, db_path: Path | None) -> None:
        self.db_path = db_path
        self._stamp: tuple[FileStamp, FileStamp] | None = None

    def reading(self) -> None:
        """Called as a read starts: a write made while it reads is still noticed after."""
        self._stamp = league_stamp(self.db_path)

    def changed(self) -> bool:
        """Written to since the last read started (by anyone, this app included)."""
        return league_stamp(self.db_path) != self._stamp

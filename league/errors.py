"""The league's user-facing error: one sentence saying what is wrong and what to do."""

from __future__ import annotations

from enum import Enum


class Fix(Enum):
    """A remedy that each front end offers its own way. The library's sentence names the
    command line's command; the app, which can do the same with a key, says that instead
    (`racer_tui.screens.base.error_message`)."""

    IMPORT_TRACK = "import the track"


class LeagueError(ValueError):
    """Something asked of the league that cannot be done; the message is for the user.

    `problem` is what is wrong, without the remedy, and `fix` names the remedy, when the
    message ends in a command that a front end may offer in its own words."""

    def __init__(self, message: str, *, problem: str = "", fix: Fix | None = None) -> None:
        super().__init__(message)
        self.problem = problem or message
        self.fix = fix

"""The league's user-facing error: one sentence saying what is wrong and what to do."""

from __future__ import annotations

from sim.remedies import Fix


class LeagueError(ValueError):
    """Something asked of the league that cannot be done; the message is for the user.

    `problem` is what is wrong, without the remedy, and `fix` names the remedy, when the
    message ends in a command that a front end may offer in its own words."""

    def __init__(self, message: str, *, problem: str = "", fix: Fix | None = None) -> None:
        super().__init__(message)
        self.problem = problem or message
        self.fix = fix

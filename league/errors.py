"""The league's user-facing error: one sentence saying what is wrong and what to do."""

from __future__ import annotations

from sim.foundation.remedies import RemedyError


class LeagueError(RemedyError):
    """Something asked of the league that cannot be done; the message is for the user
    (with its `problem` and `fix` when it ends in a command a front end words its own way)."""

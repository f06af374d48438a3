"""The league's user-facing error: one sentence saying what is wrong and what to do."""

from __future__ import annotations


class LeagueError(ValueError):
    """Something asked of the league that cannot be done; the message is for the user."""

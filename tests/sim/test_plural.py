"""Counts read as words: one row, two rows."""

from __future__ import annotations

from sim.foundation.plural import counted


def test_one_is_singular_and_the_rest_plural() -> None:
    assert counted(1, "row") == "1 row"
    assert counted(0, "row") == "0 rows"
    assert counted(2, "entry", "entries") == "2 entries"
    assert counted(12000, "lap") == "12,000 laps"

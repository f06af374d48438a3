"""Rows read by column name (league.rows): the query's order does not matter, a column with
no field of its name is refused, fields the query does not give keep their defaults."""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass

import pytest

from league.rows import row_as, rows_as


@dataclass
class Lap:
    number: int
    seconds: float
    note: str = "-"


def _conn() -> sqlite3.Connection:
    conn = sqlite3.connect(":memory:")
    conn.execute("CREATE TABLE laps (number INTEGER, seconds REAL, note TEXT)")
    conn.executemany("INSERT INTO laps VALUES (?, ?, ?)", [(1, 9.5, "a"), (2, 8.25, "b")])
    return conn


def test_columns_go_to_the_fields_of_their_names_in_any_order() -> None:
    conn = _conn()
    in_order = rows_as(Lap, conn.execute("SELECT number, seconds, note FROM laps"))
    shuffled = rows_as(Lap, conn.execute("SELECT note, seconds, number FROM laps"))
    assert in_order == shuffled == [Lap(1, 9.5, "a"), Lap(2, 8.25, "b")]


def test_fields_no_column_names_keep_their_defaults() -> None:
    conn = _conn()
    assert rows_as(Lap, conn.execute("SELECT seconds, number FROM laps ORDER BY number")) == [
        Lap(1, 9.5),
        Lap(2, 8.25),
    ]


def test_a_column_with_no_field_of_its_name_is_refused() -> None:
    conn = _conn()
    with pytest.raises(ValueError, match="time"):
        rows_as(Lap, conn.execute("SELECT number, seconds AS time FROM laps"))


def test_one_row_by_name() -> None:
    conn = _conn()
    conn.row_factory = sqlite3.Row
    row = conn.execute("SELECT seconds, number FROM laps WHERE number = 2").fetchone()
    assert row_as(Lap, row) == Lap(2, 8.25)

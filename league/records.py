"""Shared rows as records: what sync pushes and pulls.

A record is one row of a shared table: its id, and its body = every column except `id`
and `content_hash`, plus the child laps of submissions and races (as the row's `laps`
list, in lap order). A column added after records were first shared (OPTIONAL_COLUMNS, and
a lap's `Children.optional`) is in the body only when it holds a value, so older records
keep their content hash.
`content_hash == sim.foundation.ids.content_hash(body)` for every row; the league computes it when
it inserts a row, and `record_body` rebuilds the body from the database so anyone can
check it.

`store_record` inserts a record that came from elsewhere (checked by the caller) with its
laps, and refreshes the local caches it affects. Call it inside `league.transaction()`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from league.assembler import LAP_COLUMNS as SUBMISSION_LAP_COLUMNS
from league.assembler import OPTIONAL_LAP_COLUMNS as OPTIONAL_SUBMISSION_LAP_COLUMNS
from league.entries import refresh_entries
from league.errors import LeagueError
from league.races import LAP_COLUMNS as RACE_LAP_COLUMNS
from league.races import OPTIONAL_LAP_COLUMNS as OPTIONAL_RACE_LAP_COLUMNS
from league.store import League
from sim.foundation.ids import content_hash


@dataclass(frozen=True)
class Children:
    table: str
    parent_column: str
    columns: tuple[str, ...]
    optional: frozenset[str]  # added later: in a child's body only when it holds a value

    def body(self, values: Sequence[Any]) -> dict[str, Any]:
        """A child's body from its stored values, in `columns` order."""
        return {
            column: value
            for column, value in zip(self.columns, values, strict=True)
            if not (column in self.optional and value is None)
        }

    def fits(self, lap: object) -> bool:
        """Whether `lap` has every column a child needs and no other."""
        return isinstance(lap, Mapping) and (
            set(self.columns) - self.optional <= set(lap) <= set(self.columns)
        )


# Shared tables, parents before the rows that refer to them (the order to insert in).
SHARED_TABLES: dict[str, Children | None] = {
    "roster": None,  # first: whether a pulled record is allowed depends on it
    "racers": None,
    "tracks": None,
    "seasons": None,
    "nights": None,
    "night_entrants": None,
    "heats": None,
    "night_closures": None,
    "night_changes": None,
    "brackets": None,  # its seeds are the night's entrant ids, as JSON in the row
    "head_to_heads": None,  # its cars and their laps are JSON in the row
    "submissions": Children(
        "submission_laps",
        "submission_id",
        SUBMISSION_LAP_COLUMNS,
        OPTIONAL_SUBMISSION_LAP_COLUMNS,
    ),
    "races": Children("race_laps", "race_id", RACE_LAP_COLUMNS, OPTIONAL_RACE_LAP_COLUMNS),
    "corrections": None,
}


# Columns later versions added to shared tables; a record without them is still whole.
OPTIONAL_COLUMNS: dict[str, frozenset[str]] = {
    "nights": frozenset({"held_on"}),
    "submissions": frozenset({"physics", "race_type"}),
    "races": frozenset({"physics", "runtime"}),
}


def _check_table(table: str) -> Children | None:
    if table not in SHARED_TABLES:
        raise LeagueError(f"{table!r} is not a shared league table.")
    return SHARED_TABLES[table]


def _columns(league: League, table: str) -> list[str]:
    return [row[1] for row in league.query(f"PRAGMA table_info({table})")]


def record_body(league: League, table: str, record_id: str) -> dict[str, Any]:
    """The body of one shared row, exactly as its content hash was taken."""
    children = _check_table(table)
    row = league.query_one(f"SELECT * FROM {table} WHERE id = ?", (record_id,))
    if row is None:
        raise LeagueError(f"there is no {table} row {record_id}.")
    body = row_body(table, dict(row))
    if children is not None:
        laps = league.query(
            f"SELECT {', '.join(children.columns)} FROM {children.table} "
            f"WHERE {children.parent_column} = ? ORDER BY number",
            (record_id,),
        )
        body["laps"] = [children.body(tuple(lap)) for lap in laps]
    return body


def row_body(table: str, row: Mapping[str, Any]) -> dict[str, Any]:
    """A shared row's own fields as its record body holds them (without its laps)."""
    optional = OPTIONAL_COLUMNS.get(table, frozenset())
    return {
        key: value
        for key, value in row.items()
        if key not in ("id", "content_hash") and not (key in optional and value is None)
    }


def records(league: League, table: str) -> Iterator[tuple[str, str, dict[str, Any]]]:
    """(id, stored content hash, body) of every row of a shared table, in id order."""
    _check_table(table)
    for row in league.query(f"SELECT id, content_hash FROM {table} ORDER BY id"):
        yield row[0], row[1], record_body(league, table, row[0])


def store_record(
    league: League,
    table: str,
    record_id: str,
    body: Mapping[str, Any],
    *,
    refresh: bool = True,
) -> bool:
    """Insert a record from elsewhere; False if that id is already here with the same hash.

    LeagueError for the same id with other content (a conflict), or a body whose keys are
    not the table's columns. The content hash is computed here, never taken on trust.
    `refresh=False` leaves the leaderboard cache to the caller, who inserts many records
    and then calls refresh_entries once for all of them (in the same transaction).
    """
    children = _check_table(table)
    digest = content_hash(dict(body))
    existing = league.query_one(f"SELECT content_hash FROM {table} WHERE id = ?", (record_id,))
    if existing is not None:
        if existing[0] == digest:
            return False
        raise LeagueError(f"{table} record {record_id} is here with different content.")
    fields = {key: value for key, value in body.items() if key != "laps"}
    columns = [c for c in _columns(league, table) if c not in ("id", "content_hash")]
    required = set(columns) - OPTIONAL_COLUMNS.get(table, frozenset())
    if not required <= set(fields) <= set(columns) or (children is not None) != ("laps" in body):
        raise LeagueError(f"{table} record {record_id} does not have the table's fields.")
    names = ["id", *columns, "content_hash"]
    values = [record_id, *(fields.get(c) for c in columns), digest]
    with league.transaction():
        league.conn.execute(
            f"INSERT INTO {table} ({', '.join(names)}) VALUES ({', '.join('?' for _ in names)})",
            values,
        )
        if children is not None:
            laps = body["laps"]
            if not isinstance(laps, list) or not all(children.fits(lap) for lap in laps):
                raise LeagueError(f"{table} record {record_id} has malformed laps.")
            league.conn.executemany(
                f"INSERT INTO {children.table} ({children.parent_column}, "
                f"{', '.join(children.columns)}) "
                f"VALUES (?, {', '.join('?' for _ in children.columns)})",
                [(record_id, *(lap.get(c) for c in children.columns)) for lap in laps],
            )
            if refresh:
                refresh_entries(league.conn, [record_id])
        elif refresh and table == "corrections" and fields.get("kind") == "disqualify_lap":
            refresh_entries(league.conn, [str(fields["target"])])
    return True

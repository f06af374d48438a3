"""The league database: one SQLite file, and the League every command reads and writes it by.

league.opening.open_league() opens it. Every multi-row change goes through
`League.transaction()`, one `BEGIN IMMEDIATE` transaction, so a failure or a Ctrl+C leaves
no partial rows.

Shared rows (racers, tracks, submissions, races, nights, entrants, heats, seasons,
corrections) are immutable: each has a 26-character time-sortable `id` (sim.foundation.ids.new_id)
and a `content_hash` = sim.foundation.ids.content_hash(record body), where the body is every shared
column except `id` and `content_hash` (plus the laps for submissions and races). Sync can
therefore push and pull rows as they are; a change is always a new row (a correction).
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from types import TracebackType
from typing import Any

import sqlite_utils

from league.errors import LeagueError
from sim.foundation.home import league_db_file
from sim.foundation.ids import content_hash, new_id

__all__ = ["League", "LeagueError", "default_db_path", "now_iso", "record_body"]


def default_db_path() -> Path:
    return league_db_file()


def now_iso() -> str:
    """Current UTC time as ISO-8601 with milliseconds; sorts as text in time order."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


class League:
    """An open league database. Use as a context manager, or call `close()`."""

    def __init__(self, path: Path, conn: sqlite3.Connection) -> None:
        self.path = path
        self.conn = conn
        # sqlite-utils for convenient single-row inserts and table introspection; it nests
        # its own writes as savepoints inside our transaction.
        self.db = sqlite_utils.Database(conn, execute_plugins=False)

    def __enter__(self) -> League:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self.conn.close()

    @contextmanager
    def transaction(self) -> Iterator[None]:
        """One atomic change. Nested calls become savepoints of the outer transaction.

        BEGIN IMMEDIATE takes the write lock up front, so two processes writing at once
        wait for each other (busy timeout) instead of failing half-way.
        """
        if self.conn.in_transaction:
            with self.db.atomic():
                yield
            return
        self.conn.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            if self.conn.in_transaction:
                self.conn.execute("ROLLBACK")
            raise
        self.conn.execute("COMMIT")

    def query(self, sql: str, params: Any = ()) -> list[sqlite3.Row]:
        return list(self.conn.execute(sql, params))

    def query_one(self, sql: str, params: Any = ()) -> sqlite3.Row | None:
        row: sqlite3.Row | None = self.conn.execute(sql, params).fetchone()
        return row

    def insert_record(
        self,
        table: str,
        fields: Mapping[str, Any],
        *,
        record_id: str | None = None,
        children: Mapping[str, Any] | None = None,
    ) -> str:
        """Insert one shared row: a new id (unless given) and the content hash of its body.

        `children` (e.g. {"laps": [...]}) are part of the record's body for the hash but
        are inserted by the caller into their own table.
        """
        row_id = record_id or new_id()
        body = record_body(fields, children)
        row = {"id": row_id, **fields, "content_hash": content_hash(body)}
        columns = ", ".join(row)
        marks = ", ".join("?" for _ in row)
        self.conn.execute(f"INSERT INTO {table} ({columns}) VALUES ({marks})", list(row.values()))
        return row_id


def record_body(
    fields: Mapping[str, Any], children: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """What a shared record's content hash is taken over: its fields and its child rows."""
    body = {key: value for key, value in fields.items() if key not in ("id", "content_hash")}
    if children:
        body.update(children)
    return body

"""How shared rows refer to each other, read from the league's own schema.

- References (foreign keys): a pulled record whose racer, track, night... is not here
  yet waits in `sync_pending` instead of failing; a DynamoDB pull returns records in
  shard order, not creation order, so a submission can arrive before its racer.
- Natural keys (UNIQUE columns other than the id): racers by name, tracks by content
  hash, seasons by name, a night's closure by night. Two machines can each create "the
  same" row with different ids; identity.py decides which one the league keeps.

Read from `PRAGMA foreign_key_list` / `index_list`, so a migration that adds a reference
is honoured without touching sync.
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass
from typing import Any

from league.records import SHARED_TABLES
from league.store import League
from league.sync.kinds import KIND_OF_TABLE


@dataclass(frozen=True)
class Reference:
    column: str  # in the referring table
    table: str  # the referred-to table
    target: str  # its column


@dataclass(frozen=True)
class Links:
    references: dict[str, tuple[Reference, ...]]
    natural_keys: dict[str, tuple[str, ...]]  # table -> its single-column UNIQUE keys


# Every league at one schema version has the same links: read them once per version.
_BY_VERSION: dict[int, Links] = {}


def links(league: League) -> Links:
    version = int(league.conn.execute("PRAGMA user_version").fetchone()[0])
    if version not in _BY_VERSION:
        _BY_VERSION[version] = _read_links(league.conn)
    return _BY_VERSION[version]


def _read_links(conn: sqlite3.Connection) -> Links:
    references: dict[str, tuple[Reference, ...]] = {}
    natural_keys: dict[str, tuple[str, ...]] = {}
    for table in SHARED_TABLES:
        references[table] = tuple(
            Reference(row[3], row[2], row[4])
            for row in conn.execute(f"PRAGMA foreign_key_list({table})")
        )
        keys: list[str] = []
        for index in conn.execute(f"PRAGMA index_list({table})"):
            if index[2] and index[3] == "u":  # unique, from a UNIQUE constraint
                columns = [row[2] for row in conn.execute(f"PRAGMA index_info({index[1]})")]
                if len(columns) == 1:
                    keys.append(columns[0])
        natural_keys[table] = tuple(keys)
    return Links(references, natural_keys)


def missing_references(league: League, table: str, body: dict[str, Any]) -> list[str]:
    """What `body` refers to that this league does not hold, e.g. ["racer 'ana'"]."""
    missing = []
    for reference in links(league).references[table]:
        value = body.get(reference.column)
        if value is None:
            continue
        found = league.query_one(
            f"SELECT 1 FROM {reference.table} WHERE {reference.target} = ?", (value,)
        )
        if found is None:
            missing.append(f"{KIND_OF_TABLE.get(reference.table, reference.table)} {value!r}")
    return missing


def referenced_by_id(league: League, table: str, record_id: str) -> bool:
    """Whether any shared row refers to this row by its id (not by a natural key)."""
    for referring, references in links(league).references.items():
        for reference in references:
            if reference.table == table and reference.target == "id":
                found = league.query_one(
                    f"SELECT 1 FROM {referring} WHERE {reference.column} = ? LIMIT 1",
                    (record_id,),
                )
                if found is not None:
                    return True
    return False

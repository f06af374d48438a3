"""The identity rule: one row per natural key, the same one on every machine.

Two machines can each create racer "ana" (or import the same track, or close the same
night) before they ever sync: two records with different ids and one natural key. Every
machine applies the same rule, so all of them end up with the same league:

    the record with the lowest id wins (ids sort by creation time: the first one made);
    the other is kept as an alias of it in `sync_aliases`, still shared, never shown.

If the winner arrives at a machine that holds the loser, the loser row is swapped out for
the winner in one transaction. Racers and tracks are referred to by their natural key
(name, track hash), so every record that referred to the loser now refers to the winner,
and both racers' results end up under one racer with the winner's display name and colour.

A row referred to by its *id* cannot be swapped (seasons: nights refer to them by id).
Then the machine keeps its own and reports a conflict; `sync status` shows both sides.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Literal

from league.records import record_body, store_record
from league.store import League
from league.sync.kinds import TABLE_OF_KIND
from league.sync.links import links, referenced_by_id
from league.sync.local import add_conflict, body_text
from league.sync.record import SyncRecord

Resolution = Literal["aliased", "replaced", "conflict", "known"]


@dataclass(frozen=True)
class Clash:
    """A local row with the same natural key as an incoming record, and another id."""

    column: str
    local_id: str
    local_hash: str


def find_clash(league: League, record: SyncRecord) -> Clash | None:
    table = TABLE_OF_KIND[record.kind]
    for column in links(league).natural_keys[table]:
        value = record.body.get(column)
        if value is None:
            continue
        # The column's own collation applies: racer and season names match ignoring case.
        row = league.query_one(
            f"SELECT id, content_hash FROM {table} WHERE {column} = ? AND id <> ?",
            (value, record.record_id),
        )
        if row is not None:
            return Clash(column, str(row[0]), str(row[1]))
    return None


def resolve(league: League, store: str, record: SyncRecord, clash: Clash) -> Resolution:
    """Apply the identity rule to `record` and the clashing local row (in a transaction)."""
    table = TABLE_OF_KIND[record.kind]
    if record.record_id > clash.local_id:
        _add_alias(league, record, clash.local_id)
        return "aliased"
    if referenced_by_id(league, table, clash.local_id):
        local = record_body(league, table, clash.local_id)
        new = add_conflict(
            league,
            store,
            record.kind,
            record.record_id,
            f"this league's {record.kind} {clash.local_id} and the store's {record.record_id} "
            f"share the {clash.column} {record.body[clash.column]!r}; this league keeps its own "
            "because other records refer to it by id",
            local=(clash.local_hash, 0, body_text(local)),
            remote=(record.content_hash, 0, body_text(record.body)),
        )
        return "conflict" if new else "known"
    loser = record_body(league, table, clash.local_id)
    _add_alias(
        league,
        SyncRecord(record.kind, clash.local_id, clash.local_hash, loser),
        record.record_id,
    )
    league.conn.execute(
        "UPDATE sync_aliases SET canonical_id = ? WHERE kind = ? AND canonical_id = ?",
        (record.record_id, record.kind, clash.local_id),
    )
    # Rows that refer to the loser by its natural key refer to the winner once it is in;
    # checking them at commit (not at the DELETE) lets the swap happen in between.
    league.conn.execute("PRAGMA defer_foreign_keys = ON")
    league.conn.execute(f"DELETE FROM {table} WHERE id = ?", (clash.local_id,))
    store_record(league, table, record.record_id, record.body, refresh=False)
    return "replaced"


def _add_alias(league: League, record: SyncRecord, canonical_id: str) -> None:
    league.conn.execute(
        "INSERT OR IGNORE INTO sync_aliases (kind, record_id, canonical_id, content_hash, body) "
        "VALUES (?, ?, ?, ?, ?)",
        (
            record.kind,
            record.record_id,
            canonical_id,
            record.content_hash,
            body_text(record.body),
        ),
    )


def alias_hash(league: League, kind: str, record_id: str) -> str | None:
    row = league.query_one(
        "SELECT content_hash FROM sync_aliases WHERE kind = ? AND record_id = ?",
        (kind, record_id),
    )
    return None if row is None else str(row[0])


def alias_body(league: League, kind: str, record_id: str) -> dict[str, object] | None:
    row = league.query_one(
        "SELECT body FROM sync_aliases WHERE kind = ? AND record_id = ?", (kind, record_id)
    )
    return None if row is None else dict(json.loads(row[0]))

"""What a push sends: every shared record this store is not known to hold.

Sources, parents first: the league's shared tables (league.records.SHARED_TABLES), the
aliases the identity rule set aside (still part of the shared union), and the bundle
records. Racer profiles go separately, one at a time (profiles.py).

Bodies are read in batches (one query for the rows and one for their laps per batch) and
are exactly league.records.record_body's; each must hash to the row's stored content
hash, or it is reported as damaged and not sent (a receiver would reject it anyway).
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Final

from league.records import SHARED_TABLES, Children, row_body
from league.store import League
from league.sync import models
from league.sync.errors import RecordInvalidError
from league.sync.kinds import BUNDLE_KIND, KIND_OF_TABLE, MODEL_KIND
from league.sync.record import SyncRecord

BATCH: Final = 1000
_NOT_IN_STORE: Final = (
    "NOT EXISTS (SELECT 1 FROM sync_in_store s WHERE s.store = ? AND s.kind = ? "
    "AND s.record_id = {id} AND s.content_hash = {hash}) AND NOT EXISTS (SELECT 1 FROM "
    "sync_conflicts k WHERE k.store = ? AND k.kind = ? AND k.record_id = {id})"
)


@dataclass
class Batch:
    records: list[SyncRecord] = field(default_factory=list)
    damaged: list[str] = field(default_factory=list)  # one sentence per row not sent


def _table_filter(table: str) -> str:
    return _NOT_IN_STORE.format(id=f"{table}.id", hash=f"{table}.content_hash")


def count_unsent(league: League, store: str) -> int:
    total = 0
    for table in SHARED_TABLES:
        kind = KIND_OF_TABLE[table]
        row = league.query_one(
            f"SELECT count(*) FROM {table} WHERE {_table_filter(table)}",
            (store, kind, store, kind),
        )
        total += int(row[0]) if row else 0
    for source, kind_sql in (
        ("sync_aliases", "sync_aliases.kind"),
        ("sync_bundles", f"'{BUNDLE_KIND}'"),
    ):
        row = league.query_one(
            f"SELECT count(*) FROM {source} WHERE NOT EXISTS (SELECT 1 FROM sync_in_store s "
            f"WHERE s.store = ? AND s.kind = {kind_sql} AND s.record_id = {source}.record_id "
            f"AND s.content_hash = {source}.content_hash)",
            (store,),
        )
        total += int(row[0]) if row else 0
    return total + models.count_unsent(league, store)


def unsent_batches(league: League, store: str, batch: int = BATCH) -> Iterator[Batch]:
    """Batches of records to push, parents before children; ids in creation order."""
    for table, children in SHARED_TABLES.items():
        kind = KIND_OF_TABLE[table]
        rows = league.query(
            f"SELECT id, content_hash FROM {table} WHERE {_table_filter(table)} ORDER BY id",
            (store, kind, store, kind),
        )
        for start in range(0, len(rows), batch):
            chunk = rows[start : start + batch]
            bodies = _bodies(league, table, children, [row[0] for row in chunk])
            yield _records(kind, [(row[0], row[1], bodies[row[0]]) for row in chunk])
    aliases = league.query(
        "SELECT kind, record_id, content_hash, body FROM sync_aliases a WHERE NOT EXISTS "
        "(SELECT 1 FROM sync_in_store s WHERE s.store = ? AND s.kind = a.kind AND "
        "s.record_id = a.record_id AND s.content_hash = a.content_hash) ORDER BY record_id",
        (store,),
    )
    bundles = league.query(
        "SELECT record_id, content_hash, model_hash, sha256, size, name FROM sync_bundles b "
        "WHERE NOT EXISTS (SELECT 1 FROM sync_in_store s WHERE s.store = ? AND s.kind = ? "
        "AND s.record_id = b.record_id AND s.content_hash = b.content_hash) ORDER BY record_id",
        (store, BUNDLE_KIND),
    )
    extra = Batch()
    for kind, record_id, digest, body in aliases:
        extra.records.extend(_records(kind, [(record_id, digest, json.loads(body))]).records)
    for record_id, digest, model_hash, sha256, size, name in bundles:
        body = {"model_hash": model_hash, "sha256": sha256, "size": size, "name": name}
        found = _records(BUNDLE_KIND, [(record_id, digest, body)])
        extra.records.extend(found.records)
        extra.damaged.extend(found.damaged)
    found = _records(MODEL_KIND, models.unsent_models(league, store))
    extra.records.extend(found.records)
    extra.damaged.extend(found.damaged)
    if extra.records or extra.damaged:
        yield extra


def _records(kind: str, rows: Sequence[tuple[str, str, dict[str, Any]]]) -> Batch:
    out = Batch()
    for record_id, stored_hash, body in rows:
        try:
            # Checks the body against the hash the row was stored with.
            out.records.append(SyncRecord(kind, record_id, stored_hash, body))
        except RecordInvalidError as exc:
            out.damaged.append(
                f"{kind} {record_id} was not pushed: {exc} (was the league database changed "
                "outside racer-tui?)"
            )
    return out


def _bodies(
    league: League, table: str, children: Children | None, ids: list[str]
) -> dict[str, dict[str, Any]]:
    """record_body for many rows at once."""
    id_list = json.dumps(ids)
    cursor = league.conn.execute(
        f"SELECT * FROM {table} WHERE id IN (SELECT value FROM json_each(?))", (id_list,)
    )
    names = [column[0] for column in cursor.description]
    bodies: dict[str, dict[str, Any]] = {}
    for values in cursor:
        row = dict(zip(names, values, strict=True))
        bodies[row["id"]] = row_body(table, row)
    if children is not None:
        for body in bodies.values():
            body["laps"] = []
        laps = league.conn.execute(
            f"SELECT {children.parent_column}, {', '.join(children.columns)} "
            f"FROM {children.table} WHERE {children.parent_column} IN "
            "(SELECT value FROM json_each(?)) "
            f"ORDER BY {children.parent_column}, number",
            (id_list,),
        )
        for parent, *values in laps:
            bodies[parent]["laps"].append(children.body(values))
    return bodies

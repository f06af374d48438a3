"""What a pull does with a page of records: validate, then insert into the league.

`check_page` runs first and touches nothing: every record is checked against its kind's
schema (validate.py) and a bad one becomes a quarantine entry. `apply_page` then runs
inside the page's transaction and decides, record by record (parents first):

- already here with the same content (or kept as an alias): nothing to do;
- here with other content: a conflict, both sides kept;
- refers to something not here yet: waits in sync_pending;
- same natural key as a local row with another id: the identity rule (identity.py);
- otherwise: inserted through league.records.store_record.

Records that were waiting are retried once a page inserts something, and the
leaderboard cache is refreshed once for the page's submissions and races.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from league.entries import refresh_entries
from league.records import record_body, store_record
from league.store import League
from league.sync import bundle_records, identity, profiles
from league.sync.errors import RecordInvalidError
from league.sync.kinds import BUNDLE_KIND, INSERT_ORDER, PROFILE_KIND, TABLE_OF_KIND
from league.sync.links import missing_references
from league.sync.local import (
    add_conflict,
    add_pending,
    body_text,
    pending_records,
    remove_pending,
)
from league.sync.protocol import RecordRef
from league.sync.record import Quarantined, SyncRecord, quarantine
from league.sync.validate import check_record

# "known": a conflict already reported (by this sync's push, or an earlier sync).
Outcome = Literal["inserted", "already", "aliased", "replaced", "conflict", "known", "waiting"]


@dataclass(frozen=True)
class Refused:
    """A pulled record that failed its kind's checks (kind and id are known to be valid)."""

    item: Quarantined
    kind: str
    record_id: str


def check_page(records: Sequence[SyncRecord]) -> tuple[list[SyncRecord], list[Refused]]:
    """Split a page into records fit to insert and refused ones; touches nothing."""
    good: list[SyncRecord] = []
    refused: list[Refused] = []
    for record in records:
        try:
            check_record(record)
        except RecordInvalidError as exc:
            where = f"{record.kind} {record.record_id}"
            item = quarantine(str(exc), where, record.canonical_body)
            refused.append(Refused(item, record.kind, record.record_id))
        else:
            good.append(record)
    return good, refused


@dataclass
class PageResult:
    inserted: int = 0
    already: int = 0
    aliased: int = 0
    conflicts: list[str] = field(default_factory=list)
    in_store: list[RecordRef] = field(default_factory=list)  # held by the store as pulled


def apply_page(league: League, store: str, records: Sequence[SyncRecord]) -> PageResult:
    """Insert a checked page (call inside the page's transaction)."""
    result = PageResult()
    touched: list[str] = []
    for record in sorted(records, key=lambda r: (INSERT_ORDER[r.kind], r.record_id)):
        outcome = _apply(league, store, record, touched)
        _count(result, record, outcome)
        if outcome not in ("conflict", "known"):
            result.in_store.append(RecordRef.of(record))
    if result.inserted or result.aliased:
        _retry_pending(league, store, result, touched)
    if touched:
        refresh_entries(league.conn, touched)
    return result


def retry_waiting(league: League, store: str) -> PageResult:
    """Retry every waiting record once more (call inside a transaction): what it refers
    to may have been made here since (a racer added locally, say)."""
    result = PageResult()
    touched: list[str] = []
    _retry_pending(league, store, result, touched)
    if touched:
        refresh_entries(league.conn, touched)
    return result


def _count(result: PageResult, record: SyncRecord, outcome: Outcome) -> None:
    if outcome in ("inserted", "replaced"):
        result.inserted += 1
    if outcome in ("aliased", "replaced"):  # replaced: the local row became the alias
        result.aliased += 1
    if outcome == "already":
        result.already += 1
    elif outcome == "conflict":
        result.conflicts.append(f"{record.kind} {record.record_id}")


def _retry_pending(league: League, store: str, result: PageResult, touched: list[str]) -> None:
    """Insert waiting records whose references have arrived, until nothing more moves."""
    progress = True
    while progress:
        progress = False
        waiting = sorted(pending_records(league), key=lambda r: (INSERT_ORDER[r.kind], r.record_id))
        done: list[tuple[str, str]] = []
        for record in waiting:
            outcome = _apply(league, store, record, touched, retry=True)
            if outcome != "waiting":
                done.append((record.kind, record.record_id))
                _count(result, record, outcome)
                progress = progress or outcome in ("inserted", "replaced", "aliased")
        remove_pending(league, done)


def _apply(
    league: League, store: str, record: SyncRecord, touched: list[str], *, retry: bool = False
) -> Outcome:
    if record.kind == PROFILE_KIND:
        return profiles.apply_pulled_profile(league, store, record)
    if record.kind == BUNDLE_KIND:
        return bundle_records.apply_pulled_bundle(league, store, record)
    table = TABLE_OF_KIND[record.kind]
    here = league.query_one(f"SELECT content_hash FROM {table} WHERE id = ?", (record.record_id,))
    if here is not None:
        if here[0] == record.content_hash:
            return "already"
        local = record_body(league, table, record.record_id)
        return _conflict(league, store, record, str(here[0]), body_text(local))
    alias = identity.alias_hash(league, record.kind, record.record_id)
    if alias is not None:
        if alias == record.content_hash:
            return "already"
        body = identity.alias_body(league, record.kind, record.record_id)
        return _conflict(league, store, record, alias, body_text(body))
    missing = missing_references(league, table, record.body)
    if missing:
        if not retry:
            add_pending(league, record, ", ".join(missing))
        return "waiting"
    clash = identity.find_clash(league, record)
    if clash is not None:
        return identity.resolve(league, store, record, clash)
    store_record(league, table, record.record_id, record.body, refresh=False)
    if table in ("submissions", "races"):
        touched.append(record.record_id)
    elif record.kind == "correction" and record.body["kind"] == "disqualify_lap":
        touched.append(str(record.body["target"]))
    return "inserted"


def _conflict(
    league: League, store: str, record: SyncRecord, local_hash: str, local_body: str
) -> Literal["conflict", "known"]:
    new = add_conflict(
        league,
        store,
        record.kind,
        record.record_id,
        f"{record.kind} {record.record_id} has different content here and in the store; "
        "both are kept, this league shows its own",
        local=(local_hash, 0, local_body),
        remote=(record.content_hash, 0, body_text(record.body)),
    )
    return "conflict" if new else "known"

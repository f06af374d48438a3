"""Sync's local bookkeeping: this machine's knowledge about its stores, never shared.

Tables (migration 3 in league.migrations):

- `sync_settings`: the league's store URL and bundle URL (`racer-tui sync set`), and the
  last sync that failed, until one succeeds (`last_failure`: store, when, the sentence).
- `sync_in_store`: which records each store is known to hold (pushed from here, or pulled
  from it), by store URL, so a push sends only what is new and a second push sends nothing.
- `sync_cursors`: where the last pull from each store stopped (saved in the page's
  transaction, so a pull killed at any point resumes without gaps or duplicates).
- `sync_runs`: the last push and pull summary per store, for `sync status`.
- `sync_conflicts`: a record whose id this league holds with other content than the
  store, with both sides (nothing is overwritten; `sync status` shows them).
- `sync_quarantine`: pulled records that failed validation: where, why, an excerpt; and
  valid records the roster does not allow (league.trust), kept whole in `held` so they
  are tried again when the roster changes (an admission arrives).
- `sync_pending`: valid pulled records waiting for a record they refer to (a submission
  that arrived before its racer); retried after every page.
- `sync_aliases`: shared records that lost the identity rule (see identity.py).
- `sync_profiles`, `sync_bundles`, `sync_models`: the sync-level kinds (profiles.py,
  bundle_sync.py, models.py; a model record's `seen` is the order this league first
  held it in).
- `sync_first_seen`: when this league first saw a pulled result that would have won a
  tie by an early date; it ranks from then (dates.py).

Every function here runs inside the caller's transaction.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Final

from league.store import League, now_iso
from league.sync.protocol import RecordRef
from league.sync.record import Quarantined, Seal, SyncRecord, quarantine
from sim.foundation.ids import canonical_json

STORE_SETTING: Final = "store"
BUNDLES_SETTING: Final = "bundles"
FAILURE_SETTING: Final = "last_failure"


def get_setting(league: League, name: str) -> str | None:
    row = league.query_one("SELECT value FROM sync_settings WHERE name = ?", (name,))
    return None if row is None else str(row[0])


def set_setting(league: League, name: str, value: str) -> None:
    league.conn.execute(
        "INSERT INTO sync_settings (name, value) VALUES (?, ?) "
        "ON CONFLICT (name) DO UPDATE SET value = excluded.value",
        (name, value),
    )


def body_text(body: Any) -> str:
    return canonical_json(body).decode("utf-8")


# --- what a store holds --------------------------------------------------------------------


def mark_in_store(league: League, store: str, refs: Iterable[RecordRef]) -> None:
    league.conn.executemany(
        "INSERT INTO sync_in_store (store, kind, record_id, content_hash, version) "
        "VALUES (?, ?, ?, ?, ?) ON CONFLICT (store, kind, record_id) DO UPDATE SET "
        "content_hash = excluded.content_hash, version = excluded.version",
        [(store, ref.kind, ref.record_id, ref.content_hash, ref.version) for ref in refs],
    )


def in_store_count(league: League, store: str) -> int:
    row = league.query_one("SELECT count(*) FROM sync_in_store WHERE store = ?", (store,))
    return int(row[0]) if row else 0


# --- pull position and run summaries -------------------------------------------------------


def load_cursor(league: League, store: str) -> str | None:
    row = league.query_one("SELECT cursor FROM sync_cursors WHERE store = ?", (store,))
    return None if row is None else str(row[0])


def save_cursor(league: League, store: str, cursor: str) -> None:
    league.conn.execute(
        "INSERT INTO sync_cursors (store, cursor, updated_at) VALUES (?, ?, ?) "
        "ON CONFLICT (store) DO UPDATE SET cursor = excluded.cursor, "
        "updated_at = excluded.updated_at",
        (store, cursor, now_iso()),
    )


def record_run(league: League, store: str, direction: str, summary: dict[str, Any]) -> None:
    league.conn.execute(
        "INSERT INTO sync_runs (store, direction, finished_at, summary) VALUES (?, ?, ?, ?) "
        "ON CONFLICT (store, direction) DO UPDATE SET finished_at = excluded.finished_at, "
        "summary = excluded.summary",
        (store, direction, now_iso(), json.dumps(summary, sort_keys=True)),
    )


@dataclass(frozen=True)
class Failure:
    """A sync that failed: the store, when (ISO, UTC) and the sentence saying why."""

    store: str
    at: str
    message: str


def record_failure(league: League, store: str, message: str) -> None:
    body = {"store": store, "at": now_iso(), "message": message}
    set_setting(league, FAILURE_SETTING, json.dumps(body, sort_keys=True))


def clear_failure(league: League) -> None:
    league.conn.execute("DELETE FROM sync_settings WHERE name = ?", (FAILURE_SETTING,))


def last_failure(league: League) -> Failure | None:
    """The last failed sync, until a sync succeeds (None for an unreadable entry)."""
    raw = get_setting(league, FAILURE_SETTING)
    if raw is None:
        return None
    try:
        body = json.loads(raw)
        return Failure(str(body["store"]), str(body["at"]), str(body["message"]))
    except (ValueError, TypeError, KeyError):
        return None


@dataclass(frozen=True)
class Run:
    direction: str
    finished_at: str
    summary: dict[str, Any]


def runs(league: League, store: str) -> list[Run]:
    return [
        Run(row[0], row[1], json.loads(row[2]))
        for row in league.query(
            "SELECT direction, finished_at, summary FROM sync_runs WHERE store = ? "
            "ORDER BY direction",
            (store,),
        )
    ]


# --- conflicts -----------------------------------------------------------------------------


@dataclass(frozen=True)
class ConflictRow:
    """Both sides of a conflict. Bodies are canonical JSON text, or None when unknown
    (a push learns only the store's hash; the next pull brings its body)."""

    store: str
    kind: str
    record_id: str
    detail: str
    local_hash: str | None
    local_version: int
    local_body: str | None
    remote_hash: str | None
    remote_version: int
    remote_body: str | None
    found_at: str


def add_conflict(
    league: League,
    store: str,
    kind: str,
    record_id: str,
    detail: str,
    *,
    local: tuple[str | None, int, str | None],
    remote: tuple[str | None, int, str | None],
) -> bool:
    """Record (or refresh) a conflict; a body already known is kept when this one is None.

    True if the conflict is new (not known from an earlier push or pull)."""
    known = league.query_one(
        "SELECT 1 FROM sync_conflicts WHERE store = ? AND kind = ? AND record_id = ?",
        (store, kind, record_id),
    )
    league.conn.execute(
        """
        INSERT INTO sync_conflicts (store, kind, record_id, detail, local_hash, local_version,
            local_body, remote_hash, remote_version, remote_body, found_at)
        VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)
        ON CONFLICT (store, kind, record_id) DO UPDATE SET
            detail = excluded.detail,
            local_hash = coalesce(excluded.local_hash, local_hash),
            local_version = excluded.local_version,
            local_body = coalesce(excluded.local_body, local_body),
            remote_hash = coalesce(excluded.remote_hash, remote_hash),
            remote_version = excluded.remote_version,
            remote_body = coalesce(excluded.remote_body, remote_body)
        """,
        (store, kind, record_id, detail, *local, *remote, now_iso()),
    )
    return known is None


def conflicts(league: League, store: str | None = None) -> list[ConflictRow]:
    where, params = ("WHERE store = ?", (store,)) if store is not None else ("", ())
    return [
        ConflictRow(*row)
        for row in league.query(
            "SELECT store, kind, record_id, detail, local_hash, local_version, local_body, "
            "remote_hash, remote_version, remote_body, found_at FROM sync_conflicts "
            f"{where} ORDER BY found_at, kind, record_id",
            params,
        )
    ]


# --- quarantine ----------------------------------------------------------------------------


@dataclass(frozen=True)
class QuarantineRow:
    store: str
    location: str
    reason: str
    kind: str | None
    record_id: str | None
    excerpt: str
    found_at: str


def add_quarantined(
    league: League,
    store: str,
    item: Quarantined,
    kind: str | None = None,
    record_id: str | None = None,
) -> None:
    league.conn.execute(
        "INSERT INTO sync_quarantine (store, location, reason, kind, record_id, excerpt, "
        "found_at) VALUES (?, ?, ?, ?, ?, ?, ?) ON CONFLICT (store, location) DO UPDATE SET "
        "reason = excluded.reason, kind = excluded.kind, record_id = excluded.record_id, "
        "excerpt = excluded.excerpt, found_at = excluded.found_at",
        (store, item.where, item.reason, kind, record_id, item.excerpt, now_iso()),
    )


def hold(league: League, store: str, record: SyncRecord, reason: str) -> None:
    """Quarantine a valid record its signer may not make, keeping it whole to try again."""
    seal = record.seal
    held = {
        "kind": record.kind,
        "id": record.record_id,
        "content_hash": record.content_hash,
        "version": record.version,
        "body": record.body,
        "signer": None if seal is None else seal.signer,
        "signature": None if seal is None else seal.signature,
    }
    item = quarantine(reason, f"{record.kind} {record.record_id}", record.canonical_body)
    add_quarantined(league, store, item, record.kind, record.record_id)
    league.conn.execute(
        "UPDATE sync_quarantine SET held = ? WHERE store = ? AND location = ?",
        (body_text(held), store, item.where),
    )


@dataclass(frozen=True)
class Held:
    store: str
    location: str
    record: SyncRecord


def held_records(league: League) -> list[Held]:
    """Every held record, re-validated by SyncRecord (they were checked when pulled)."""
    out = []
    for store, location, text in league.query(
        "SELECT store, location, held FROM sync_quarantine WHERE held IS NOT NULL ORDER BY location"
    ):
        data = json.loads(text)
        seal = None if data["signer"] is None else Seal(data["signer"], data["signature"])
        record = SyncRecord(
            data["kind"], data["id"], data["content_hash"], data["body"], data["version"], seal
        )
        out.append(Held(str(store), str(location), record))
    return out


def release_held(league: League, held: Held) -> None:
    league.conn.execute(
        "DELETE FROM sync_quarantine WHERE store = ? AND location = ?", (held.store, held.location)
    )


def quarantined(league: League, store: str | None = None) -> list[QuarantineRow]:
    where, params = ("WHERE store = ?", (store,)) if store is not None else ("", ())
    return [
        QuarantineRow(*row)
        for row in league.query(
            "SELECT store, location, reason, kind, record_id, excerpt, found_at "
            f"FROM sync_quarantine {where} ORDER BY found_at, location",
            params,
        )
    ]


# --- records waiting for their references --------------------------------------------------


def add_pending(league: League, record: SyncRecord, waiting_for: str) -> None:
    league.conn.execute(
        "INSERT INTO sync_pending (kind, record_id, content_hash, body, waiting_for, "
        "received_at) VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (kind, record_id) DO UPDATE SET "
        "waiting_for = excluded.waiting_for",
        (
            record.kind,
            record.record_id,
            record.content_hash,
            body_text(record.body),
            waiting_for,
            now_iso(),
        ),
    )


def pending_records(league: League) -> list[SyncRecord]:
    """The waiting records, re-validated by SyncRecord (they were checked when pulled)."""
    return [
        SyncRecord(row[0], row[1], row[2], json.loads(row[3]))
        for row in league.query(
            "SELECT kind, record_id, content_hash, body FROM sync_pending ORDER BY record_id"
        )
    ]


def remove_pending(league: League, keys: Sequence[tuple[str, str]]) -> None:
    league.conn.executemany("DELETE FROM sync_pending WHERE kind = ? AND record_id = ?", list(keys))


@dataclass(frozen=True)
class PendingRow:
    kind: str
    record_id: str
    waiting_for: str
    received_at: str


def pending(league: League) -> list[PendingRow]:
    return [
        PendingRow(*row)
        for row in league.query(
            "SELECT kind, record_id, waiting_for, received_at FROM sync_pending "
            "ORDER BY received_at, record_id"
        )
    ]

"""Editable display names: a racer's versioned `racer_profile` record.

A rename stays what it always was in the league: a `rename_racer` correction row, the
audit trail every machine shows. Sync adds the concurrency check. Before a rename
correction is pushed, a profile record `{racer, display_name, correction}` with version
N + 1 (N = the newest profile version this machine knows) goes to the store, which takes
it only if it still holds version N (phase 1's conditional write). If it does not, or if
this machine pulled a newer version after the rename was made offline, the rename is
stale: it is not shared, and it moves out of the league into `sync_conflicts` (kept, shown
by `sync status`), so every machine still shows the same names. The racer is told to
pull first and rename again.

The profile's id comes from the racer's name (kinds.profile_id), so every machine edits
the same profile even if each made its own racer row before syncing.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Literal

from league.records import record_body
from league.rows import row_as
from league.store import League, now_iso
from league.sync.kinds import PROFILE_KIND, profile_id
from league.sync.local import add_conflict, body_text, mark_in_store
from league.sync.protocol import RecordRef, RecordStore, VersionConflict
from league.sync.record import SyncRecord, make_record
from league.sync.sealing import seal_all
from league.trust.keys import SigningKey

Applied = Literal["inserted", "already", "conflict", "known"]


@dataclass(frozen=True)
class KnownProfile:
    version: int
    content_hash: str
    body: dict[str, str]
    received_at: str | None  # None: this machine's own edit

    def record(self, racer: str) -> SyncRecord:
        return SyncRecord(
            PROFILE_KIND, profile_id(racer), self.content_hash, dict(self.body), self.version
        )


def known_profile(league: League, pid: str) -> KnownProfile | None:
    row = league.query_one(
        "SELECT version, content_hash, body, received_at FROM sync_profiles WHERE profile_id = ?",
        (pid,),
    )
    if row is None:
        return None
    return KnownProfile(
        int(row["version"]),
        str(row["content_hash"]),
        dict(json.loads(row["body"])),
        row["received_at"],
    )


def _save(league: League, record: SyncRecord, received_at: str | None) -> None:
    league.conn.execute(
        "INSERT INTO sync_profiles (profile_id, racer, version, content_hash, body, received_at) "
        "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (profile_id) DO UPDATE SET racer = excluded.racer, "
        "version = excluded.version, content_hash = excluded.content_hash, "
        "body = excluded.body, received_at = excluded.received_at",
        (
            record.record_id,
            record.body["racer"],
            record.version,
            record.content_hash,
            body_text(record.body),
            received_at,
        ),
    )


def apply_pulled_profile(league: League, store: str, record: SyncRecord) -> Applied:
    """Keep the newest version of each profile (a pull may bring several)."""
    known = known_profile(league, record.record_id)
    if known is None or record.version > known.version:
        _save(league, record, now_iso())
        return "inserted"
    if record.version < known.version or record.content_hash == known.content_hash:
        return "already"
    new = add_conflict(
        league,
        store,
        PROFILE_KIND,
        record.record_id,
        f"racer {record.body['racer']!r}'s profile version {record.version} differs here "
        "and in the store",
        local=(known.content_hash, known.version, body_text(known.body)),
        remote=(record.content_hash, record.version, body_text(record.body)),
    )
    return "conflict" if new else "known"


@dataclass
class ProfilePush:
    """What the profile step of a push did: profiles sent, and renames refused as stale."""

    pushed: int = 0
    skipped: int = 0
    refused: list[str] = field(default_factory=list)  # one sentence each


@dataclass(frozen=True)
class _Rename:
    correction_id: str
    racer: str
    new_name: str
    created_at: str


@dataclass(frozen=True)
class _Newer:
    """The profile version that made a rename stale."""

    version: int
    content_hash: str | None
    display_name: object  # None when only the store's hash is known


def push_profiles(
    league: League, store: RecordStore, store_key: str, signing_key: SigningKey
) -> ProfilePush:
    """Send a profile version for every rename not yet in this store, oldest first.

    Each profile goes alone: the store checks it against the version before it, so two
    renames of one racer must arrive in order.
    """
    outcome = ProfilePush()
    rows = league.query(
        "SELECT c.id AS correction_id, c.target AS racer, c.new_value AS new_name, c.created_at "
        "FROM corrections c "
        "WHERE c.kind = 'rename_racer' AND NOT EXISTS (SELECT 1 FROM sync_in_store s "
        "WHERE s.store = ? AND s.kind = 'correction' AND s.record_id = c.id) "
        "AND NOT EXISTS (SELECT 1 FROM sync_conflicts k WHERE k.store = ? "
        "AND k.kind = 'correction' AND k.record_id = c.id) ORDER BY c.created_at, c.id",
        (store_key, store_key),
    )
    for row in rows:
        rename = row_as(_Rename, row)
        known = known_profile(league, profile_id(rename.racer))
        if known is not None and known.body.get("correction") == rename.correction_id:
            record = known.record(rename.racer)  # sent before; its bookkeeping may be lost
        elif (
            known is not None
            and known.received_at is not None
            and (known.received_at > rename.created_at)
        ):
            # Pulled after the rename was made: the racer renamed what they had not seen.
            newer = _Newer(known.version, known.content_hash, known.body.get("display_name"))
            _refuse(league, store_key, rename, newer, outcome)
            continue
        else:
            body = {
                "racer": rename.racer,
                "display_name": rename.new_name,
                "correction": rename.correction_id,
            }
            version = (known.version if known else 0) + 1
            record = make_record(PROFILE_KIND, profile_id(rename.racer), body, version)
        record = seal_all(league, [record], signing_key)[0]
        report = store.push([record])
        if report.accepted:
            with league.transaction():
                _save(league, record, None)
                mark_in_store(league, store_key, [RecordRef.of(record)])
            outcome.pushed += len(report.pushed)
            outcome.skipped += len(report.skipped)
            continue
        conflict = report.conflicts[0]
        if isinstance(conflict, VersionConflict):
            newer = _Newer(conflict.remote_version, conflict.remote_hash, None)
        else:
            newer = _Newer(0, conflict.remote_hash, None)
        _refuse(league, store_key, rename, newer, outcome)
    return outcome


def _refuse(
    league: League, store_key: str, rename: _Rename, newer: _Newer, outcome: ProfilePush
) -> None:
    """Move a stale rename out of the league (kept with both sides in sync_conflicts)."""
    shown = f" to {newer.display_name!r}" if isinstance(newer.display_name, str) else ""
    detail = (
        f"your rename of racer {rename.racer!r} to {rename.new_name!r} was not shared: they "
        f"were renamed{shown} on another machine (profile version {newer.version}) after "
        "you made it; pull first, then rename again if you still want it"
    )
    correction_id = rename.correction_id
    body = record_body(league, "corrections", correction_id)
    with league.transaction():
        local_hash = league.query_one(
            "SELECT content_hash FROM corrections WHERE id = ?", (correction_id,)
        )
        add_conflict(
            league,
            store_key,
            "correction",
            correction_id,
            detail,
            local=(None if local_hash is None else str(local_hash[0]), 0, body_text(body)),
            remote=(newer.content_hash, newer.version, None),
        )
        shared_elsewhere = league.query_one(
            "SELECT 1 FROM sync_in_store WHERE kind = 'correction' AND record_id = ?",
            (correction_id,),
        )
        # Never shared: it leaves the league (kept in the conflict row). Shared through
        # another store already: it stays, and its conflict row keeps it from this store.
        if shared_elsewhere is None:
            league.conn.execute("DELETE FROM corrections WHERE id = ?", (correction_id,))
    outcome.refused.append(detail)

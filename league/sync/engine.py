"""Sync a league with a store: push what is new here, pull what is new there.

    from league.sync.engine import sync, store_key
    from league.sync import open_store
    with open_league(path) as league, open_store(url) as store:
        summary = sync(league, store, store_key(url))

Push: racer profiles (one conditional write per rename,
profiles.py), then every shared record the store is not known to hold, in batches,
parents first, each sealed (league.sync.sealing: signed here, or the maker's seal kept
from the pull it came in). The store writes
each record create-only; after each batch, one transaction records what the store now
holds (and any conflicts with both sides). A push killed at any point loses at most one
batch of bookkeeping: pushing again finds those records already in the store (skipped),
so nothing is duplicated.

Pull: page by page from the saved cursor. Each page is validated (seals included) before
anything touches the database, then inserted in one transaction together with the new
cursor, so a pull killed at any point resumes exactly where the last committed page ended.
Records whose signer the roster does not allow are held in quarantine and tried again as
the roster changes; results whose key was revoked are withdrawn. Records pulled are
recorded as held by the store, so they are never pushed back to it.

Restore: after the pull, every record this machine signed that the store should hold is
checked there, and one that was deleted or replaced (by anyone who can write to the
store) is written back as a spare copy (restore.py), so a machine pulling afresh still
finds the genuine record beside any forgery.

An unreachable store raises a SyncError (one sentence) before anything local changes.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any, Final

from league.store import League
from league.sync import incoming, local, models, outgoing, profiles
from league.sync.errors import CursorInvalidError
from league.sync.protocol import ContentConflict, PullPage, RecordStore, VersionConflict
from league.sync.record import KINDS, SyncRecord
from league.sync.restore import restore_own_records
from league.sync.sealing import seal_all
from league.sync.urls import parse_store_url
from league.trust.keys import SigningKey, load_or_create_key
from league.trust.membership import propose_key
from sim.foundation.ids import ID_PATTERN

# Called as progress(direction, done, total) with direction "push" or "pull"; a pull's
# total is unknown (None) until its last page.
Progress = Callable[[str, int, int | None], None]
PULL_PAGE: Final = 1000
_KIND_IN_PLACE: Final = re.compile(
    rf"(?<![a-z_])({'|'.join(sorted(KINDS, key=len, reverse=True))})(?![a-z_])"
)


def store_key(url: str) -> str:
    """The canonical form of a store URL: what the league's bookkeeping is keyed by."""
    return str(parse_store_url(url))


@dataclass
class SyncSummary:
    """What one sync did. Lists hold one plain-text sentence per item (untrusted text
    from the store inside: show it as plain text, never as markup)."""

    store: str
    pushed: int = 0
    pulled: int = 0
    skipped: int = 0  # the store already held them (a push that was interrupted, say)
    already_here: int = 0  # pulled, but this league had them (its own records, mostly)
    aliased: int = 0  # same racer/track made on two machines: kept as an alias
    waiting: int = 0  # pulled records waiting for a record they refer to
    conflicts: list[str] = field(default_factory=list)
    quarantined: list[str] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)  # stale renames
    damaged: list[str] = field(default_factory=list)  # local rows that could not be sent
    released: int = 0  # held records the roster now allows (an admission arrived)
    withdrawn: list[str] = field(default_factory=list)  # results of revoked keys taken out
    notes: list[str] = field(default_factory=list)  # e.g. why this machine's key is unproposed

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    def merged(self, other: SyncSummary) -> SyncSummary:
        return SyncSummary(
            self.store,
            self.pushed + other.pushed,
            self.pulled + other.pulled,
            self.skipped + other.skipped,
            self.already_here + other.already_here,
            self.aliased + other.aliased,
            other.waiting,
            self.conflicts + other.conflicts,
            self.quarantined + other.quarantined,
            self.refused + other.refused,
            self.damaged + other.damaged,
            self.released + other.released,
            self.withdrawn + other.withdrawn,
            self.notes + other.notes,
        )


def sync(
    league: League,
    store: RecordStore,
    key: str,
    *,
    push_records: bool = True,
    pull_records: bool = True,
    progress: Progress | None = None,
    signing_key: SigningKey | None = None,
) -> SyncSummary:
    """Push, then pull (so a conflict found by the push gets the store's side at once).
    `signing_key` seals what this machine sends (default: the data directory's key).

    Then, if the league (as just pulled) does not know this machine's key, the key is
    proposed to the organiser under the racer's saved name and the proposal pushed: after
    the pull, so the organiser's own machines never propose themselves."""
    summary = SyncSummary(key)
    if not push_records:  # a pull signs nothing: it needs no key
        return summary.merged(pull(league, store, key, progress=progress))
    signing = signing_key or load_or_create_key()
    summary = summary.merged(push(league, store, key, progress=progress, signing_key=signing))
    if pull_records:
        summary = summary.merged(pull(league, store, key, progress=progress))
    summary.notes.extend(restore_own_records(league, store, key, signing.public_hex))
    if pull_records:
        proposed, note = propose_key(league, signing)
        if note is not None:
            summary.notes.append(note)
        # An organiser's word on whose each model is goes out in the same sync as the
        # claims it settles: a machine pulling afresh before the organiser's next sync
        # would otherwise see only the racers' claims, whose ids and dates can be forged.
        endorsed = models.endorse_if_organiser(league, signing.public_hex)
        if proposed or endorsed:
            summary = summary.merged(push(league, store, key, signing_key=signing))
    return summary


# --- push ------------------------------------------------------------------------------------


def push(
    league: League,
    store: RecordStore,
    key: str,
    *,
    progress: Progress | None = None,
    batch: int = outgoing.BATCH,
    signing_key: SigningKey | None = None,
) -> SyncSummary:
    summary = SyncSummary(key)
    signing = signing_key or load_or_create_key()
    store.push([])  # reach the store (or fail with one sentence) before doing anything
    renames = profiles.push_profiles(league, store, key, signing)
    models.register_models(league, signing.public_hex)  # the models this racer raced
    summary.pushed += renames.pushed
    summary.skipped += renames.skipped
    summary.refused.extend(renames.refused)
    total = outgoing.count_unsent(league, key)
    done = 0
    if progress is not None:
        progress("push", 0, total)
    for chunk in outgoing.unsent_batches(league, key, batch):
        summary.damaged.extend(chunk.damaged)
        if not chunk.records:
            continue
        sent_before = done

        def report_progress(sent: int, _of: int, before: int = sent_before) -> None:
            if progress is not None:
                progress("push", min(before + sent, total), total)

        sealed = seal_all(league, chunk.records, signing)
        report = store.push(sealed, progress=report_progress)
        by_key = {record.key: record for record in chunk.records}
        with league.transaction():
            local.mark_in_store(league, key, report.accepted)
            for conflict in report.conflicts:
                _record_push_conflict(league, key, conflict, by_key)
        summary.pushed += len(report.pushed)
        summary.skipped += len(report.skipped)
        summary.conflicts.extend(conflict.describe() for conflict in report.conflicts)
        done += len(chunk.records)
        if progress is not None:
            progress("push", min(done, total), total)
    with league.transaction():
        local.record_run(league, key, "push", _counts(summary))
    return summary


def _record_push_conflict(
    league: League,
    key: str,
    conflict: ContentConflict | VersionConflict,
    by_key: dict[tuple[str, str], SyncRecord],
) -> None:
    record = by_key.get((conflict.kind, conflict.record_id))
    local_version = conflict.local_version if isinstance(conflict, VersionConflict) else 0
    remote_version = conflict.remote_version if isinstance(conflict, VersionConflict) else 0
    local.add_conflict(
        league,
        key,
        conflict.kind,
        conflict.record_id,
        conflict.describe(),
        local=(
            conflict.local_hash,
            local_version,
            None if record is None else local.body_text(record.body),
        ),
        remote=(conflict.remote_hash, remote_version, None),
    )


# --- pull ------------------------------------------------------------------------------------


def pull(
    league: League,
    store: RecordStore,
    key: str,
    *,
    progress: Progress | None = None,
    page_size: int = PULL_PAGE,
) -> SyncSummary:
    summary = SyncSummary(key)
    cursor = local.load_cursor(league, key)
    page = _first_page(league, store, key, cursor, page_size)
    seen = 0
    while True:
        records, refused = incoming.check_page(page.records)
        with league.transaction():
            result = incoming.apply_page(league, key, records)
            for item in page.quarantined:
                kind, record_id = _kind_and_id(item.where)
                local.add_quarantined(league, key, item, kind, record_id)
            for bad in refused:
                local.add_quarantined(league, key, bad.item, bad.kind, bad.record_id)
            local.mark_in_store(league, key, result.in_store)
            local.save_cursor(league, key, page.next_cursor)
        summary.pulled += result.inserted
        summary.already_here += result.already
        summary.aliased += result.aliased
        summary.conflicts.extend(
            f"{what}: differs here and in the store (both kept)" for what in result.conflicts
        )
        summary.quarantined.extend(
            f"{item.where}: {item.reason}"
            for item in (*page.quarantined, *(bad.item for bad in refused))
        )
        summary.quarantined.extend(result.held)
        summary.released += result.released
        seen += len(page.records) + len(page.quarantined)
        if progress is not None:
            progress("pull", seen, None if page.more else seen)
        if not page.more:
            break
        page = store.pull(page.next_cursor, limit=page_size)
    with league.transaction():
        late = incoming.retry_waiting(league, key)
        summary.withdrawn.extend(incoming.withdraw_refused(league, key))
    summary.pulled += late.inserted
    summary.aliased += late.aliased
    summary.quarantined.extend(late.held)  # refused now that what they waited for came
    summary.released += late.released
    summary.conflicts.extend(
        f"{what}: differs here and in the store (both kept)" for what in late.conflicts
    )
    summary.waiting = len(local.pending(league))
    with league.transaction():
        local.record_run(league, key, "pull", _counts(summary))
    return summary


def _first_page(
    league: League, store: RecordStore, key: str, cursor: str | None, page_size: int
) -> PullPage:
    try:
        return store.pull(cursor, limit=page_size)
    except CursorInvalidError:
        # A damaged position (or one from an older store at this URL): start over. Pulling
        # everything again is safe: records already here are skipped.
        return store.pull(None, limit=page_size)


def _kind_and_id(where: str) -> tuple[str | None, str | None]:
    """The kind and id a store's quarantine location names, when it names valid ones."""
    kind = _KIND_IN_PLACE.search(where)
    record_id = ID_PATTERN.search(where)
    return (kind[1] if kind else None), (record_id[0] if record_id else None)


def _counts(summary: SyncSummary) -> dict[str, Any]:
    return {
        "pushed": summary.pushed,
        "pulled": summary.pulled,
        "skipped": summary.skipped,
        "already_here": summary.already_here,
        "aliased": summary.aliased,
        "waiting": summary.waiting,
        "conflicts": len(summary.conflicts),
        "quarantined": len(summary.quarantined),
        "refused": len(summary.refused),
    }

"""What every store does, and what it reports back.

All stores share one contract so the league's sync code never knows which one it talks to:

- `push(records)` writes each record create-only: new -> pushed; already there with the
  same hash -> skipped; already there with another hash -> a conflict carrying both
  hashes (never overwritten). A versioned record (`racer_profile`) replaces the stored
  one only when the stored version is the one it was edited from (its version - 1); a
  stale writer gets a `VersionConflict`. Each record is written atomically, so a push
  killed halfway leaves whole records only, and re-running it completes the rest.
- `pull(cursor)` returns what was added since `cursor` (None = from the start), one
  page at a time; keep calling with `next_cursor` while `more` is true, and save
  `next_cursor` only after the page's records are stored locally. A pull may return a
  record the caller already has (inserts must be idempotent by key and hash), and may
  return several versions of a versioned record (keep the highest).
- `held_copies(keys, spares=)` reads what the store holds under each record's key (and
  its spare copies), and `write_spare(record)` writes a record again after its copy in the
  store was deleted or replaced: under its own key if that is free, else as the first free
  of SPARE_SLOTS spare copies. Records are immutable, but anyone who can write to a shared
  folder or table can still replace one; its maker puts it back (league.sync.restore).
- `close()` releases connections; stores are also context managers.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

from league.sync.record import VERSIONED_KINDS, Quarantined, SyncRecord

# Called as progress(done, total) while a push runs, from the calling thread.
ProgressCallback = Callable[[int, int], None]
DEFAULT_PAGE_SIZE = 500
# Spare copies a record may have beside its own key: a maker whose record was replaced
# writes it again in the next free one, so a forger must fill them all to keep it out,
# and then the maker is told.
SPARE_SLOTS = 8


@dataclass(frozen=True)
class RecordRef:
    """Which record (and which content) a report line is about."""

    kind: str
    record_id: str
    content_hash: str
    version: int = 0

    @classmethod
    def of(cls, record: SyncRecord) -> RecordRef:
        return cls(record.kind, record.record_id, record.content_hash, record.version)


@dataclass(frozen=True)
class ContentConflict:
    """The store holds another content under this record's key; nothing was overwritten.

    `remote_hash` is None when the stored copy is unreadable (it will be quarantined
    when pulled).
    """

    kind: str
    record_id: str
    local_hash: str
    remote_hash: str | None

    def describe(self) -> str:
        remote = self.remote_hash[:12] if self.remote_hash else "unreadable"
        return (
            f"{self.kind} {self.record_id}: the store holds different content "
            f"({remote}) from this league ({self.local_hash[:12]})"
        )


@dataclass(frozen=True)
class VersionConflict:
    """A versioned record was edited from a version the store no longer holds."""

    kind: str
    record_id: str
    local_version: int
    remote_version: int
    local_hash: str
    remote_hash: str | None

    def describe(self) -> str:
        return (
            f"{self.kind} {self.record_id}: this league's version {self.local_version} was "
            f"edited from version {self.local_version - 1}, but the store has version "
            f"{self.remote_version}; pull first, then edit again"
        )


Conflict = ContentConflict | VersionConflict


@dataclass(frozen=True)
class PushReport:
    """The outcome of a push, record by record."""

    pushed: tuple[RecordRef, ...] = ()
    skipped: tuple[RecordRef, ...] = ()
    conflicts: tuple[Conflict, ...] = ()

    def __add__(self, other: PushReport) -> PushReport:
        return PushReport(
            self.pushed + other.pushed,
            self.skipped + other.skipped,
            self.conflicts + other.conflicts,
        )

    @property
    def accepted(self) -> tuple[RecordRef, ...]:
        """Records the store now holds exactly as given (pushed now or before)."""
        return self.pushed + self.skipped


@dataclass(frozen=True)
class PullPage:
    """One page of a pull: valid records, refused ones, and where to continue."""

    records: tuple[SyncRecord, ...]
    quarantined: tuple[Quarantined, ...]
    next_cursor: str
    more: bool


class RecordStore(Protocol):
    """A shared store of records (see the module docstring for the contract)."""

    @property
    def description(self) -> str:
        """The store's URL-like name, for messages."""
        ...

    def init(self) -> None:
        """Create what the store needs (folder, table); safe to run again."""
        ...

    def push(
        self, records: Iterable[SyncRecord], progress: ProgressCallback | None = None
    ) -> PushReport: ...

    def pull(self, cursor: str | None = None, limit: int = DEFAULT_PAGE_SIZE) -> PullPage: ...

    def held_copies(
        self, keys: Sequence[tuple[str, str]], *, spares: bool = False
    ) -> dict[tuple[str, str], list[SyncRecord]]:
        """Whole records held under each (kind, id) key (and its spare copies' keys)."""
        ...

    def write_spare(self, record: SyncRecord) -> str | None:
        """Write `record` under its own key if free, else its first free spare key;
        where it went, or None if all are taken."""
        ...

    def close(self) -> None: ...

    def __enter__(self) -> RecordStore: ...

    def __exit__(self, *exc_info: object) -> None: ...


def unique_records(
    records: Iterable[SyncRecord],
) -> tuple[list[SyncRecord], list[RecordRef], list[Conflict]]:
    """Drop repeats of a key within one push; two contents for one key is a local conflict.

    Returns (unique records in first-seen order, repeats to report as skipped, conflicts).
    """
    first: dict[tuple[str, str], SyncRecord] = {}
    repeats: list[RecordRef] = []
    conflicts: list[Conflict] = []
    for record in records:
        seen = first.get(record.key)
        if seen is None:
            first[record.key] = record
        elif seen.content_hash == record.content_hash and seen.version == record.version:
            repeats.append(RecordRef.of(record))
        elif record.kind in VERSIONED_KINDS and record.version != seen.version:
            # Two edits of one profile: only the newest goes out; the older is superseded.
            newer, older = (record, seen) if record.version > seen.version else (seen, record)
            first[record.key] = newer
            repeats.append(RecordRef.of(older))
        else:
            conflicts.append(
                ContentConflict(
                    record.kind, record.record_id, record.content_hash, seen.content_hash
                )
            )
    return list(first.values()), repeats, conflicts

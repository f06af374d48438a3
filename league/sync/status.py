"""What sync has done and set aside, for every front end: `racer-tui sync status`, the
League screen's status line and the app's Sync screen all read it from here.

    from league.sync.status import sync_overview, sync_status
    overview = sync_overview(league)   # cheap: the store, last runs and counts
    status = sync_status(league)       # plus the conflicts, quarantined records, ...

Text inside (racer names, reasons, excerpts) comes from other machines: show it as plain
text, never as markup.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from typing import Any, Final

from league.store import League
from league.sync import local
from league.sync.bundle_records import BundleInfo, bundles
from league.sync.engine import SyncSummary, store_key
from league.sync.errors import StoreUrlError
from league.sync.outgoing import count_unsent
from sim.foundation.plural import counted

EXCERPT: Final = 60  # characters of a value shown for one side of a conflict


@dataclass(frozen=True)
class Alias:
    """A racer or track made on two machines: `record_id` is kept as `canonical_id`."""

    kind: str
    record_id: str
    canonical_id: str


@dataclass(frozen=True)
class SyncOverview:
    """The figures a status line needs. `store` is the canonical URL (the raw saved text
    when it no longer parses), None when no store is set; `to_push` is None then too."""

    store: str | None
    bundles: str | None
    runs: dict[str, local.Run]  # "push" / "pull" -> the last one, when there was one
    in_store: int
    to_push: int | None
    conflicts: int
    quarantined: int
    waiting: int
    failure: local.Failure | None = None  # the last sync with this store failed

    @property
    def last_run(self) -> local.Run | None:
        """The most recent push or pull (ISO times sort as text)."""
        return max(self.runs.values(), key=lambda run: run.finished_at, default=None)

    def moved(self, direction: str) -> int | None:
        """How many records the last "push" pushed or "pull" pulled (None: never ran)."""
        run = self.runs.get(direction)
        return None if run is None else int(run.summary.get(f"{direction}ed", 0))


@dataclass(frozen=True)
class SyncStatus:
    """The overview plus everything sync set aside, with the reasons."""

    overview: SyncOverview
    conflicts: list[local.ConflictRow]
    quarantined: list[local.QuarantineRow]
    waiting: list[local.PendingRow]
    aliases: list[Alias]
    bundles_known: list[BundleInfo]

    def to_json(self) -> dict[str, Any]:
        """The document `racer-tui sync status --json` prints."""
        overview = self.overview
        return {
            "store": overview.store,
            "bundles": overview.bundles,
            "runs": {direction: asdict(run) for direction, run in overview.runs.items()},
            "last_failure": asdict(overview.failure) if overview.failure else None,
            "in_store": overview.in_store,
            "to_push": overview.to_push,
            "conflicts": [asdict(row) for row in self.conflicts],
            "quarantined": [asdict(row) for row in self.quarantined],
            "waiting": [asdict(row) for row in self.waiting],
            "aliases": [asdict(alias) for alias in self.aliases],
            "bundles_known": [asdict(info) for info in self.bundles_known],
        }


def store_key_or_none(url: str | None) -> str | None:
    """The canonical form of a saved store URL; the text as saved if it no longer parses."""
    if url is None:
        return None
    try:
        return store_key(url)
    except StoreUrlError:
        return url


def _count(league: League, table: str) -> int:
    row = league.query_one(f"SELECT count(*) FROM {table}")
    return int(row[0]) if row else 0


def sync_overview(league: League) -> SyncOverview:
    key = store_key_or_none(local.get_setting(league, local.STORE_SETTING))
    runs: dict[str, local.Run] = {}
    in_store = 0
    to_push = None
    if key is not None:
        runs = {run.direction: run for run in local.runs(league, key)}
        in_store = local.in_store_count(league, key)
        to_push = count_unsent(league, key)
    failure = local.last_failure(league)
    return SyncOverview(
        store=key,
        bundles=local.get_setting(league, local.BUNDLES_SETTING),
        runs=runs,
        in_store=in_store,
        to_push=to_push,
        conflicts=_count(league, "sync_conflicts"),
        quarantined=_count(league, "sync_quarantine"),
        waiting=_count(league, "sync_pending"),
        failure=failure if failure is not None and failure.store == key else None,
    )


def sync_status(league: League) -> SyncStatus:
    return SyncStatus(
        overview=sync_overview(league),
        conflicts=local.conflicts(league),
        quarantined=local.quarantined(league),
        waiting=local.pending(league),
        aliases=[
            Alias(str(row[0]), str(row[1]), str(row[2]))
            for row in league.query(
                "SELECT kind, record_id, canonical_id FROM sync_aliases ORDER BY kind, record_id"
            )
        ],
        bundles_known=bundles(league),
    )


# --- both sides of a conflict ----------------------------------------------------------------


@dataclass(frozen=True)
class ConflictView:
    """A conflict as one table row: which fields differ, and each side in one line."""

    kind: str
    record_id: str
    what: str
    here: str
    there: str


def conflict_view(conflict: local.ConflictRow, limit: int = 3) -> ConflictView:
    fields = differing_fields(conflict.local_body, conflict.remote_body)
    if fields is not None:
        what = ", ".join(fields[:limit]) + (
            f" (+{len(fields) - limit})" if len(fields) > limit else ""
        )
    elif conflict.local_version or conflict.remote_version:
        what = f"version {conflict.local_version} here, {conflict.remote_version} in the store"
    else:
        what = "content (the store's side arrives with the next pull)"
    here, there = differences(conflict.local_body, conflict.remote_body, limit)
    return ConflictView(
        conflict.kind,
        conflict.record_id,
        what,
        side_label(conflict.local_hash, conflict.local_version, here),
        side_label(conflict.remote_hash, conflict.remote_version, there),
    )


def side_label(digest: str | None, version: int, content: str) -> str:
    label = (digest or "unknown")[:12] + (f" v{version}" if version else "")
    return f"{label}: {content}"


def differing_fields(here: str | None, there: str | None) -> list[str] | None:
    """The dotted names of the fields whose values differ; None while a body is unknown."""
    if here is None or there is None:
        return None
    ours, theirs = _flat(json.loads(here)), _flat(json.loads(there))
    return [
        name for name in sorted(ours.keys() | theirs.keys()) if ours.get(name) != theirs.get(name)
    ]


def differences(here: str | None, there: str | None, limit: int = 3) -> tuple[str, str]:
    """What differs between the two sides' bodies, field by field (a few fields at most)."""
    fields = differing_fields(here, there)
    if here is None or there is None or fields is None:
        missing = "content not pulled yet"
        return (here or missing)[:EXCERPT], (there or missing)[:EXCERPT]
    ours, theirs = _flat(json.loads(here)), _flat(json.loads(there))
    shown = fields[:limit]
    more = f" (+{len(fields) - limit} more)" if len(fields) > limit else ""

    def side(values: dict[str, Any]) -> str:
        return (
            "; ".join(f"{name}={json.dumps(values.get(name))[:EXCERPT]}" for name in shown) + more
        )

    return side(ours), side(theirs)


def _flat(value: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(value, dict):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(_flat(item, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list):
        out = {}
        for index, item in enumerate(value):
            out.update(_flat(item, f"{prefix}[{index + 1}]"))
        return out
    return {prefix: value}


# --- what one sync did, in sentences ---------------------------------------------------------


def summary_headline(summary: SyncSummary) -> str:
    conflicts = len(summary.conflicts)
    return (
        f"Synced with {summary.store}: pushed {summary.pushed}, pulled {summary.pulled}, "
        f"skipped {summary.skipped}, {conflicts} conflict{'s' * (conflicts != 1)}, "
        f"{len(summary.quarantined)} quarantined."
    )


def summary_details(summary: SyncSummary, notes: list[str], *, items: bool = True) -> list[str]:
    """One plain-text line per item set aside (unless `items` is False: a front end that
    lists conflicts and quarantined records itself), then the notes and what waits."""
    lines = [
        *(f"conflict: {line}" for line in summary.conflicts if items),
        *(f"quarantined: {line}" for line in summary.quarantined if items),
        *(f"rename not shared: {line}" for line in summary.refused),
        *(f"not pushed: {line}" for line in summary.damaged),
        *(f"withdrawn: {line}" for line in summary.withdrawn),
        *summary.notes,
        *notes,
    ]
    if summary.released:
        lines.append(
            f"{counted(summary.released, 'held record')} let in: the organiser admitted "
            "the key that signed them"
        )
    if summary.aliased:
        lines.append(
            f"{counted(summary.aliased, 'record')} made on two machines for one racer or track: "
            "the first one made is kept everywhere"
        )
    if summary.waiting:
        lines.append(
            f"{counted(summary.waiting, 'pulled record')} "
            f"{'waits' if summary.waiting == 1 else 'wait'} for records "
            f"{'it refers' if summary.waiting == 1 else 'they refer'} to; "
            f"{'it is' if summary.waiting == 1 else 'they are'} added when those arrive"
        )
    return lines

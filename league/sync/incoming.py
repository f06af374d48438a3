"""What a pull does with a page of records: validate, then insert into the league.

`check_page` runs first and touches nothing: every record must carry a genuine seal (a
signature that matches its content) and pass its kind's schema (validate.py); a bad one
becomes a quarantine entry. `apply_page` then runs inside the page's transaction and
decides, record by record (roster acts first, then parents before children):

- already here with the same content and seal: nothing to do;
- its signer may not make it (league.trust.roster): quarantined and held whole, tried
  again whenever the roster changes;
- already here with the same content (or kept as an alias): nothing to do;
- here with other content: a conflict, both sides kept;
- dated before the league was founded, by a racer: refused (dates.py);
- refers to something not here yet: waits in sync_pending;
- a result that copies another racer's, or races a model another racer registered first:
  refused; one whose model its racer has not registered yet: waits (models.py);
- same natural key as a local row with another id: the identity rule (identity.py);
- otherwise: inserted through league.records.store_record.

Records that were waiting are retried once a page inserts something, and the
leaderboard cache is refreshed once for the page's submissions and races.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final, Literal

from league.entries import rebuild_entries, refresh_entries
from league.records import record_body, store_record
from league.store import League
from league.sync import bundle_records, identity, models, profiles
from league.sync.dates import Arrivals, founding_refusal
from league.sync.errors import RecordInvalidError
from league.sync.kinds import BUNDLE_KIND, INSERT_ORDER, MODEL_KIND, PROFILE_KIND, TABLE_OF_KIND
from league.sync.links import missing_references
from league.sync.local import (
    add_conflict,
    add_pending,
    add_quarantined,
    body_text,
    held_records,
    hold,
    pending_records,
    release_held,
    remove_pending,
)
from league.sync.protocol import RecordRef
from league.sync.record import Quarantined, Seal, SyncRecord, quarantine
from league.sync.sealing import keep_seals
from league.sync.validate import check_record
from league.trust.roster import FOUNDER_ID, ROSTER_KIND, Roster
from league.trust.seals import is_genuine

# "known": a conflict already reported (by this sync's push, or an earlier sync).
Outcome = Literal[
    "inserted", "already", "aliased", "replaced", "conflict", "known", "waiting", "held"
]
_RESULT_KINDS: Final = ("submission", "race")


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
            if record.seal is None:
                raise RecordInvalidError(
                    "it is not signed, so nobody can tell who made it (a racer-tui from before "
                    "signed results, or a file written by hand)"
                )
            if not is_genuine(record):
                raise RecordInvalidError(
                    "its signature does not match its content: it was changed after it was "
                    "signed, or signed by another key than it names"
                )
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
    held: list[str] = field(default_factory=list)  # "<where>: <why>" per record held back
    released: int = 0  # held records the roster now allows
    in_store: list[RecordRef] = field(default_factory=list)  # held by the store as pulled


@dataclass
class _Trust:
    """The roster as this page changes it, and the times its results arrived at."""

    roster: Roster
    changed: bool = False
    arrivals: Arrivals = field(default_factory=Arrivals)


def _sort_key(record: SyncRecord) -> tuple[int, int, str]:
    # The founding act first: every other act is checked against the organiser it names.
    founding = record.kind == ROSTER_KIND and record.record_id == FOUNDER_ID
    return (INSERT_ORDER[record.kind], 0 if founding else 1, record.record_id)


def apply_page(league: League, store: str, records: Sequence[SyncRecord]) -> PageResult:
    """Insert a checked page (call inside the page's transaction)."""
    result = PageResult()
    touched: list[str] = []
    trust = _Trust(Roster.load(league))
    for record in sorted(records, key=_sort_key):
        outcome = _apply_trusted(league, store, record, touched=touched, trust=trust, result=result)
        _count(result, record, outcome)
        if outcome not in ("conflict", "known") and not (
            outcome == "held" and _holds_another_copy(league, record)
        ):
            result.in_store.append(RecordRef.of(record))
    if trust.changed:
        _retry_held(league, result, touched, trust)
    if result.inserted or result.aliased:
        _retry_pending(league, store, result, touched, trust.arrivals)
    if touched:
        refresh_entries(league.conn, touched)
        trust.arrivals.settle(league)
    return result


def retry_waiting(league: League, store: str) -> PageResult:
    """Retry every held and waiting record once more (call inside a transaction): the
    roster may have changed here since (an admission made on this machine), and what a
    record refers to may have been made here (a racer added locally, say)."""
    result = PageResult()
    touched: list[str] = []
    trust = _Trust(Roster.load(league), changed=True)
    _retry_held(league, result, touched, trust)
    _retry_pending(league, store, result, touched, trust.arrivals)
    if touched:
        refresh_entries(league.conn, touched)
        trust.arrivals.settle(league)
    return result


def retry_held(league: League) -> PageResult:
    """Try every held record against the roster as it is now (call inside a transaction
    after the roster changed here: an organiser admitted a key on this machine)."""
    result = PageResult()
    touched: list[str] = []
    trust = _Trust(Roster.load(league), changed=True)
    _retry_held(league, result, touched, trust)
    if touched:
        refresh_entries(league.conn, touched)
        trust.arrivals.settle(league)
    return result


# What a revoked key must lose from the boards: its results, and a co-host's lap
# disqualifications. Nothing else refers to these rows by id (laps and traces go with
# them), so taking them out leaves the league whole. A revoked key's nights, heats and
# racers stay where they are: they rank nobody, and heats' races are results.
_WITHDRAWN_KINDS: Final = {
    "submission": "submissions",
    "race": "races",
    "head_to_head": "head_to_heads",
    "correction": "corrections",
}


def withdraw_refused(league: League, store: str) -> list[str]:
    """Take out of the league every result whose seal the roster no longer accepts (its
    key was revoked, or retired before it signed), holding each in quarantine; returns
    one sentence per result withdrawn. Call inside a transaction."""
    roster = Roster.load(league)
    suspects = roster.revoked | set(roster.kept)
    if not suspects:
        return []
    withdrawn: list[str] = []
    rows = league.query(
        "SELECT kind, record_id, version, content_hash, signer, signature FROM sync_seals "
        "WHERE kind IN ('submission', 'race', 'correction') "
        "AND signer IN (SELECT value FROM json_each(?))",
        (json.dumps(sorted(suspects)),),
    )
    for kind, record_id, version, digest, signer, signature in rows:
        table = _WITHDRAWN_KINDS[kind]
        here = league.query_one(f"SELECT content_hash FROM {table} WHERE id = ?", (record_id,))
        if here is None or here[0] != digest:
            continue
        body = record_body(league, table, record_id)
        if kind == "correction" and body["kind"] != "disqualify_lap":
            continue  # a rename's display name lives on in profiles: not undone here
        record = SyncRecord(kind, record_id, digest, body, version).sealed(Seal(signer, signature))
        reason = roster.refusal(record)
        if reason is None:
            continue
        withdraw(league, store, record, reason, rebuild=False)
        withdrawn.append(f"{kind} {record_id}: {reason}")
    if withdrawn:
        rebuild_entries(league.conn)
    return withdrawn


def withdraw(
    league: League,
    store: str,
    record: SyncRecord,
    reason: str,
    *,
    rebuild: bool = True,
    final: bool = False,
) -> None:
    """Take a result (a submission, race, head-to-head race or lap disqualification) out of
    the league and hold it in quarantine with `reason` (call inside a transaction); `final`:
    never let it in again (a replay disproved it), else it is tried again when the roster
    changes."""
    table = _WITHDRAWN_KINDS[record.kind]
    if final:
        item = quarantine(reason, f"{record.kind} {record.record_id}", record.canonical_body)
        add_quarantined(league, store, item, record.kind, record.record_id)
    else:
        hold(league, store, record, reason)
    league.conn.execute(
        "DELETE FROM sync_seals WHERE kind = ? AND record_id = ?", (record.kind, record.record_id)
    )
    if record.kind == "race":
        league.conn.execute("DELETE FROM race_traces WHERE race_id = ?", (record.record_id,))
        league.conn.execute("DELETE FROM race_laps WHERE race_id = ?", (record.record_id,))
    elif record.kind == "submission":
        league.conn.execute(
            "DELETE FROM submission_laps WHERE submission_id = ?", (record.record_id,)
        )
    league.conn.execute(f"DELETE FROM {table} WHERE id = ?", (record.record_id,))
    if rebuild:
        rebuild_entries(league.conn)


def _apply_trusted(
    league: League,
    store: str,
    record: SyncRecord,
    *,
    touched: list[str],
    trust: _Trust,
    result: PageResult,
) -> Outcome:
    """The roster's rule, then `_apply`; a record the roster refuses is held. A record
    this league holds already (its own, coming back) needs no judging; a race that a
    replay here disproved is refused for good."""
    if not _already_here(league, record):
        if _disproved(league, record):
            disproof = "re-run here from its model, track, rules and seed, its laps differ"
            add_quarantined(
                league,
                store,
                quarantine(disproof, f"{record.kind} {record.record_id}", record.canonical_body),
                record.kind,
                record.record_id,
            )
            result.held.append(f"{record.kind} {record.record_id}: {disproof}")
            return "held"
        reason = trust.roster.refusal(record)
        if reason is not None:
            hold(league, store, record, reason)
            result.held.append(f"{record.kind} {record.record_id}: {reason}")
            return "held"
        too_early = founding_refusal(record, trust.roster)
        if too_early is not None:
            return _refuse(league, store, record, too_early, result.held)
        keep_seals(league, [record])
    outcome = _apply(
        league,
        store,
        record,
        touched,
        roster=trust.roster,
        refused=result.held,
        arrivals=trust.arrivals,
    )
    if record.kind == ROSTER_KIND and outcome in ("inserted", "replaced"):
        trust.roster = Roster.load(league)
        trust.changed = True
    return outcome


def _holds_another_copy(league: League, record: SyncRecord) -> bool:
    """Whether this league holds other content under the key of a record it holds back.
    Then the store's copy is someone's forgery of a record here, and the bookkeeping keeps
    saying the store holds the one here: a machine writes back only its own records that
    it knows it put in the store (league.sync.restore), and would otherwise take the
    forgery for what it had pushed."""
    table = TABLE_OF_KIND.get(record.kind)
    if table is None:
        return False
    row = league.query_one(f"SELECT content_hash FROM {table} WHERE id = ?", (record.record_id,))
    return row is not None and row[0] != record.content_hash


def _already_here(league: League, record: SyncRecord) -> bool:
    """Whether this league holds exactly this content under this key already."""
    if record.kind == PROFILE_KIND:  # the hash covers the body, not the version
        row = league.query_one(
            "SELECT 1 FROM sync_profiles WHERE profile_id = ? AND content_hash = ? AND version = ?",
            (record.record_id, record.content_hash, record.version),
        )
        return row is not None
    if record.kind == BUNDLE_KIND:
        sql = "SELECT 1 FROM sync_bundles WHERE record_id = ? AND content_hash = ?"
    elif record.kind == MODEL_KIND:
        return models.is_here(league, record.record_id, record.content_hash)
    else:
        table = TABLE_OF_KIND[record.kind]
        sql = (
            f"SELECT 1 FROM {table} WHERE id = ?1 AND content_hash = ?2 UNION ALL SELECT 1 "
            "FROM sync_aliases WHERE record_id = ?1 AND content_hash = ?2"
        )
    return league.query_one(sql, (record.record_id, record.content_hash)) is not None


def _disproved(league: League, record: SyncRecord) -> bool:
    if record.kind != "race":
        return False
    row = league.query_one(
        "SELECT 1 FROM sync_replays WHERE race_id = ? AND content_hash = ? AND outcome = 'differs'",
        (record.record_id, record.content_hash),
    )
    return row is not None


def _retry_held(league: League, result: PageResult, touched: list[str], trust: _Trust) -> None:
    """Try held records again while the roster keeps changing (an admission can let in
    an organiser whose own admissions then count)."""
    while trust.changed:
        trust.changed = False
        for held in sorted(held_records(league), key=lambda held: _sort_key(held.record)):
            if trust.roster.refusal(held.record) is not None:
                continue
            release_held(league, held)
            outcome = _apply_trusted(
                league, held.store, held.record, touched=touched, trust=trust, result=result
            )
            _count(result, held.record, outcome)
            result.released += 1


def _count(result: PageResult, record: SyncRecord, outcome: Outcome) -> None:
    if outcome in ("inserted", "replaced"):
        result.inserted += 1
    if outcome in ("aliased", "replaced"):  # replaced: the local row became the alias
        result.aliased += 1
    if outcome == "already":
        result.already += 1
    elif outcome == "conflict":
        result.conflicts.append(f"{record.kind} {record.record_id}")


def _retry_pending(
    league: League, store: str, result: PageResult, touched: list[str], arrivals: Arrivals
) -> None:
    """Insert waiting records whose references have arrived, until nothing more moves."""
    progress = True
    roster = Roster.load(league)
    while progress:
        progress = False
        waiting = sorted(pending_records(league), key=lambda r: (INSERT_ORDER[r.kind], r.record_id))
        done: list[tuple[str, str]] = []
        for record in waiting:
            # Trusted when pulled; its model is judged again, as model records arrive.
            outcome = _apply(
                league,
                store,
                record,
                touched,
                roster=roster,
                refused=result.held,
                arrivals=arrivals,
                retry=True,
            )
            if outcome != "waiting":
                done.append((record.kind, record.record_id))
                _count(result, record, outcome)
                progress = progress or outcome in ("inserted", "replaced", "aliased")
        remove_pending(league, done)


def _apply(
    league: League,
    store: str,
    record: SyncRecord,
    touched: list[str],
    *,
    roster: Roster,
    refused: list[str],
    arrivals: Arrivals,
    retry: bool = False,
) -> Outcome:
    if record.kind == PROFILE_KIND:
        return profiles.apply_pulled_profile(league, store, record)
    if record.kind == BUNDLE_KIND:
        return bundle_records.apply_pulled_bundle(league, store, record)
    if record.kind == MODEL_KIND:
        return models.apply_pulled_model(league, store, record)
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
    judged = models.verdict(league, record, roster)
    if judged is not None and judged.action == "refuse":
        return _refuse(league, store, record, judged.reason, refused)
    if judged is not None:
        if not retry:
            add_pending(league, record, judged.reason)
        return "waiting"
    clash = identity.find_clash(league, record)
    if clash is not None:
        return identity.resolve(league, store, record, clash)
    store_record(league, table, record.record_id, record.body, refresh=False)
    if record.kind in _RESULT_KINDS:
        touched.append(record.record_id)
        arrivals.note(record)  # a tie is not won by a date written early
    elif record.kind == "correction" and record.body["kind"] == "disqualify_lap":
        touched.append(str(record.body["target"]))
    return "inserted"


def _refuse(
    league: League, store: str, record: SyncRecord, reason: str, refused: list[str]
) -> Literal["held"]:
    """Quarantine a valid, genuinely signed record that can never count here (no roster
    change makes a forged date true or a copy someone's own), with `reason`."""
    where = f"{record.kind} {record.record_id}"
    add_quarantined(
        league,
        store,
        quarantine(reason, where, record.canonical_body),
        record.kind,
        record.record_id,
    )
    league.conn.execute(
        "DELETE FROM sync_seals WHERE kind = ? AND record_id = ? AND content_hash = ?",
        (record.kind, record.record_id, record.content_hash),
    )
    refused.append(f"{where}: {reason}")
    return "held"


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

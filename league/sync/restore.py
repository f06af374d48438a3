"""Put back a record that someone deleted or replaced in the store.

Records in a store are immutable and written create-only, but whoever can write to the
shared folder or the table can still delete a record, or write another body over it
with its hash recomputed so that it looks whole. Nobody's board takes the forgery (its
seal no longer matches, and the pull quarantines it with that sentence), and a machine
that pulled the record before keeps its copy. A machine pulling afresh, though, would
find only the forgery, and the honest result would be missing from its board.

So at each sync a machine checks that the store still holds, under each record's key or
as a spare copy of it, a genuine copy of every record it signed itself and pushed there,
and writes back any that is missing: under the record's own key if that is free (it was
deleted), else as the first free spare copy (league.sync.protocol.SPARE_SLOTS), which
every machine pulls like any record. Checking only this machine's own records keeps the
cost to one read per record it made; their maker is the one racer who is sure to want
them back. A machine that made more than CHECKS_PER_SYNC records (a league host's)
checks its newest half of that every sync and takes the older ones in turn, so each is
checked within a few syncs and a sync stays quick.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Final

from league.records import SHARED_TABLES, record_body
from league.store import League
from league.sync import local
from league.sync.errors import RecordInvalidError
from league.sync.kinds import KIND_OF_TABLE, MODEL_KIND
from league.sync.models import model_body
from league.sync.protocol import RecordStore
from league.sync.record import Seal, SyncRecord

_CHUNK: Final = 500  # keys read from the store at once
# Reading and checking one record in the store costs about a millisecond.
CHECKS_PER_SYNC: Final = 1000


@dataclass(frozen=True)
class _Own:
    """A record this machine signed and the store is known to hold: a row of a shared
    league `table`, or a model record (league.sync.models) whose `body` is kept here."""

    table: str | None
    kind: str
    record_id: str
    content_hash: str
    seal: Seal
    body: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def key(self) -> tuple[str, str]:
        return (self.kind, self.record_id)

    def is_copy(self, held: SyncRecord) -> bool:
        """Whether `held` is this very record under its maker's seal. A stored SyncRecord's
        body always hashes to its content hash, and the seal kept here is genuine (this
        machine made it), so the same signature over the same hash is too: no signature
        needs checking again."""
        return (
            held.content_hash == self.content_hash and held.version == 0 and held.seal == self.seal
        )


def restore_own_records(
    league: League, store: RecordStore, store_key: str, signer: str
) -> list[str]:
    """Write back each record signed by `signer` (this machine's public key) that the
    store should hold but no longer holds whole; one sentence per record written back
    or that could not be."""
    own = _this_syncs_share(league, store_key, _own_records(league, store_key, signer))
    notes: list[str] = []
    for start in range(0, len(own), _CHUNK):
        chunk = own[start : start + _CHUNK]
        held = store.held_copies([record.key for record in chunk])
        lost = [record for record in chunk if not any(map(record.is_copy, held[record.key]))]
        if lost:
            notes.extend(_write_back(league, store, lost))
    return notes


def _write_back(league: League, store: RecordStore, lost: Sequence[_Own]) -> list[str]:
    spares = store.held_copies([record.key for record in lost], spares=True)
    notes: list[str] = []
    for own in lost:
        if any(map(own.is_copy, spares[own.key])):
            continue  # written back by an earlier sync
        what = f"{own.kind} {own.record_id}"
        try:
            body = record_body(league, own.table, own.record_id) if own.table else own.body
            record = SyncRecord(own.kind, own.record_id, own.content_hash, body).sealed(own.seal)
        except RecordInvalidError:
            notes.append(
                f"{what}: its copy in the store was deleted or changed, and the one here no "
                "longer matches its hash, so it was not written back (was the league database "
                "changed outside racer-tui?)"
            )
            continue
        where = store.write_spare(record)
        if where is None:
            notes.append(
                f"{what}: its copy in the store was changed by someone else and every spare "
                "place for it is taken; ask the organiser to check who can write to the store"
            )
        else:
            notes.append(
                f"{what}: its copy in the store had been deleted or changed by someone else; "
                f"this machine wrote it back ({where})"
            )
    return notes


def _this_syncs_share(league: League, store_key: str, own: list[_Own]) -> list[_Own]:
    """All of `own` when there are few; else the newest half of CHECKS_PER_SYNC and the next
    older ones in turn after those the last sync checked (their place is kept here)."""
    if len(own) <= CHECKS_PER_SYNC:
        return own
    own.sort(key=lambda record: record.record_id)  # ids sort by the time they were made
    newest = CHECKS_PER_SYNC // 2
    older = own[:-newest]
    setting = f"restore_after:{store_key}"
    after = local.get_setting(league, setting) or ""
    start = next((i for i, record in enumerate(older) if record.record_id > after), 0)
    turn = (older[start:] + older[:start])[: CHECKS_PER_SYNC - newest]
    with league.transaction():
        local.set_setting(league, setting, turn[-1].record_id)
    return turn + own[-newest:]


def _own_records(league: League, store_key: str, signer: str) -> list[_Own]:
    own: list[_Own] = []
    for table in SHARED_TABLES:
        kind = KIND_OF_TABLE[table]
        rows = league.query(
            f"SELECT t.id, t.content_hash, s.signature FROM {table} t "
            "JOIN sync_seals s ON s.kind = ?1 AND s.record_id = t.id AND s.version = 0 "
            "AND s.content_hash = t.content_hash AND s.signer = ?2 "
            "JOIN sync_in_store i ON i.store = ?3 AND i.kind = ?1 AND i.record_id = t.id "
            "AND i.content_hash = t.content_hash ORDER BY t.id",
            (kind, signer, store_key),
        )
        own.extend(_Own(table, kind, row[0], row[1], Seal(signer, row[2])) for row in rows)
    return own + _own_models(league, store_key, signer)


def _own_models(league: League, store_key: str, signer: str) -> list[_Own]:
    """This machine's model records: without them, a fresh machine would hold its racer's
    results back, waiting for the model they name. The body is league.sync.models'."""
    rows = league.query(
        "SELECT m.record_id, m.content_hash, s.signature, m.racer, m.model_name, m.model_hash, "
        "m.registered_at FROM sync_models m "
        "JOIN sync_seals s ON s.kind = ?1 AND s.record_id = m.record_id AND s.version = 0 "
        "AND s.content_hash = m.content_hash AND s.signer = ?2 "
        "JOIN sync_in_store i ON i.store = ?3 AND i.kind = ?1 AND i.record_id = m.record_id "
        "AND i.content_hash = m.content_hash ORDER BY m.record_id",
        (MODEL_KIND, signer, store_key),
    )
    return [
        _Own(
            None,
            MODEL_KIND,
            record_id,
            digest,
            Seal(signer, signature),
            model_body(racer, model_name, model_hash, registered_at),
        )
        for record_id, digest, signature, racer, model_name, model_hash, registered_at in rows
    ]

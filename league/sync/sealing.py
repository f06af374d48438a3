"""Seals travel with their records: what a push signs, and what a pull keeps.

A record made on this machine is signed with this machine's key the first time it is
pushed; a pulled record keeps the seal its maker put on it, so pushing it on to another
store (or to a new store of the same league) sends the maker's seal, not ours. Both kinds
of seal live in `sync_seals`, keyed by kind, id, version and content hash.

Rows made before records were signed carry no seal here; they are signed by this machine
when next pushed (their makers cannot be told apart any more).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence

from league.store import League
from league.sync.record import Seal, SyncRecord
from league.trust.keys import SigningKey
from league.trust.seals import make_seal

SealKey = tuple[str, str, int, str]


def _key(record: SyncRecord) -> SealKey:
    return (record.kind, record.record_id, record.version, record.content_hash)


def keep_seals(league: League, records: Iterable[SyncRecord]) -> None:
    """Remember the seals of `records` (call inside a transaction); a seal already kept for
    the same content stays."""
    league.conn.executemany(
        "INSERT OR IGNORE INTO sync_seals (kind, record_id, version, content_hash, signer, "
        "signature) VALUES (?, ?, ?, ?, ?, ?)",
        [
            (*_key(record), record.seal.signer, record.seal.signature)
            for record in records
            if record.seal
        ],
    )


def known_seals(league: League, records: Sequence[SyncRecord]) -> dict[SealKey, Seal]:
    wanted = json.dumps([list(_key(record)) for record in records])
    rows = league.query(
        "SELECT s.kind, s.record_id, s.version, s.content_hash, s.signer, s.signature "
        "FROM json_each(?) AS w JOIN sync_seals AS s ON "
        "s.kind = json_extract(w.value, '$[0]') AND s.record_id = json_extract(w.value, '$[1]') "
        "AND s.version = json_extract(w.value, '$[2]') "
        "AND s.content_hash = json_extract(w.value, '$[3]')",
        (wanted,),
    )
    return {
        (row["kind"], row["record_id"], int(row["version"]), row["content_hash"]): Seal(
            row["signer"], row["signature"]
        )
        for row in rows
    }


def seal_all(league: League, records: Sequence[SyncRecord], key: SigningKey) -> list[SyncRecord]:
    """`records` with their seals: the kept one, or a new one by `key` (kept now)."""
    kept = known_seals(league, records)
    out: list[SyncRecord] = []
    fresh: list[SyncRecord] = []
    for record in records:
        seal = kept.get(_key(record))
        if seal is None:
            sealed = record.sealed(make_seal(record, key))
            fresh.append(sealed)
        else:
            sealed = record.sealed(seal)
        out.append(sealed)
    if fresh:
        with league.transaction():
            keep_seals(league, fresh)
    return out

"""`bundle` records: which bundle in the S3 store holds which model.

A submission or race names its car by model hash (the garage's hash of metadata and
weights, the same as its bundle's). Bundles in S3 are named by the SHA-256 of the file
instead (content-addressed, checked on download), so a small shared record maps one to
the other: `{model_hash, sha256, size, name}`. The league host reads these to fetch the
models it races (`racer-tui sync fetch-bundle`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from league.store import League
from league.sync.kinds import BUNDLE_KIND
from league.sync.local import add_conflict, body_text
from league.sync.record import SyncRecord


@dataclass(frozen=True)
class BundleInfo:
    record_id: str
    model_hash: str
    sha256: str
    size: int
    name: str


def add_bundle(league: League, record: SyncRecord) -> None:
    body = record.body
    league.conn.execute(
        "INSERT INTO sync_bundles (record_id, model_hash, sha256, size, name, content_hash) "
        "VALUES (?, ?, ?, ?, ?, ?)",
        (
            record.record_id,
            body["model_hash"],
            body["sha256"],
            body["size"],
            body["name"],
            record.content_hash,
        ),
    )


def apply_pulled_bundle(
    league: League, store: str, record: SyncRecord
) -> Literal["inserted", "already", "conflict", "known"]:
    row = league.query_one(
        "SELECT content_hash, model_hash, sha256, size, name FROM sync_bundles WHERE record_id = ?",
        (record.record_id,),
    )
    if row is None:
        add_bundle(league, record)
        return "inserted"
    if row[0] == record.content_hash:
        return "already"
    local = {"model_hash": row[1], "sha256": row[2], "size": row[3], "name": row[4]}
    new = add_conflict(
        league,
        store,
        BUNDLE_KIND,
        record.record_id,
        f"bundle record {record.record_id} differs here and in the store",
        local=(str(row[0]), 0, body_text(local)),
        remote=(record.content_hash, 0, body_text(record.body)),
    )
    return "conflict" if new else "known"


def bundles(league: League) -> list[BundleInfo]:
    return [
        BundleInfo(*row)
        for row in league.query(
            "SELECT record_id, model_hash, sha256, size, name FROM sync_bundles "
            "ORDER BY name, record_id"
        )
    ]


def find_bundles(league: League, spec: str) -> list[BundleInfo]:
    """Bundles whose model hash or file hash is `spec`, or starts with it (8+ characters)."""
    text = spec.strip().lower()
    if len(text) < 8 or not all(char in "0123456789abcdef" for char in text):
        return []
    pattern = text + "%"
    return [
        BundleInfo(*row)
        for row in league.query(
            "SELECT record_id, model_hash, sha256, size, name FROM sync_bundles "
            "WHERE model_hash LIKE ? OR sha256 LIKE ? ORDER BY record_id",
            (pattern, pattern),
        )
    ]

"""The DynamoDB table design, and the conversion between records and items.

Table (on-demand billing)::

    partition key  pk          S   "<kind>#<record id>"  one item per record: create-only puts
                                                         condition on attribute_not_exists(pk)
    attributes     content_hash (S), version (N),
                   body (S: the canonical JSON the hash is taken over, so checking a pulled
                   record is exact and floats never pass through DynamoDB's Decimal numbers),
                   shard (S), pushed_key (S; starts with the push time in ms, server clock),
                   signer, signature (S: the record's seal, absent on an unsealed record)
    GSI by_push    partition key shard (S, "0".."7" from a hash of pk),
                   sort key pushed_key (S, "<pushed_at 13 digits>#<kind>#<id>#<version>"),
                   projection ALL

Pull = for each of the 8 shards, Query by_push where shard = S and pushed_key > cursor:
new items in push order, paginated. Spreading the index over 8 shards keeps one index
partition from throttling a league night's writes; 8 queries per pull is cheap.
A fixed item pk "meta#store" marks a table set up by racer-tui (format, shard count).
Items carry no copies of what the keys already say (kind, id, push time): fewer attributes
mean smaller items and less work per item for every reader.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from typing import Any, Final

from league.sync.errors import RecordInvalidError
from league.sync.record import (
    MAX_BODY_BYTES,
    MAX_VERSION,
    Quarantined,
    SyncRecord,
    build_record,
    parse_json,
    quarantine,
    safe_text,
)

TABLE_FORMAT: Final = 1
INDEX_NAME: Final = "by_push"
SHARD_COUNT: Final = 8
META_PK: Final = "meta#store"
PK: Final = "pk"
SHARD: Final = "shard"
PUSHED_KEY: Final = "pushed_key"

Item = dict[str, Any]  # low-level client format: {"name": {"S": "..."}, ...}


def create_table_request(table: str) -> dict[str, Any]:
    return {
        "TableName": table,
        "AttributeDefinitions": [
            {"AttributeName": PK, "AttributeType": "S"},
            {"AttributeName": SHARD, "AttributeType": "S"},
            {"AttributeName": PUSHED_KEY, "AttributeType": "S"},
        ],
        "KeySchema": [{"AttributeName": PK, "KeyType": "HASH"}],
        "BillingMode": "PAY_PER_REQUEST",
        "GlobalSecondaryIndexes": [
            {
                "IndexName": INDEX_NAME,
                "KeySchema": [
                    {"AttributeName": SHARD, "KeyType": "HASH"},
                    {"AttributeName": PUSHED_KEY, "KeyType": "RANGE"},
                ],
                "Projection": {"ProjectionType": "ALL"},
            }
        ],
    }


def table_design_problem(description: Mapping[str, Any]) -> str | None:
    """Why an existing table cannot be a racer-tui store, or None if its keys fit."""
    keys = [(key["AttributeName"], key["KeyType"]) for key in description.get("KeySchema", [])]
    if keys != [(PK, "HASH")]:
        return f"its primary key is {keys}, not ({PK}, HASH)"
    for index in description.get("GlobalSecondaryIndexes", []):
        if index.get("IndexName") == INDEX_NAME:
            index_keys = [(key["AttributeName"], key["KeyType"]) for key in index["KeySchema"]]
            if index_keys != [(SHARD, "HASH"), (PUSHED_KEY, "RANGE")]:
                return f"its {INDEX_NAME} index has the keys {index_keys}"
            if index.get("Projection", {}).get("ProjectionType") != "ALL":
                return f"its {INDEX_NAME} index does not project all attributes"
            return None
    return f"it has no {INDEX_NAME} index"


def meta_item() -> Item:
    return {
        PK: {"S": META_PK},
        "format": {"N": str(TABLE_FORMAT)},
        "shards": {"N": str(SHARD_COUNT)},
        "created_by": {"S": "racer-tui"},
    }


def meta_problem(item: Mapping[str, Any] | None) -> str | None:
    """Why the meta item does not describe a store this racer-tui can use."""
    if item is None:
        return "missing"
    if item.get("format") != {"N": str(TABLE_FORMAT)}:
        return "newer"
    if item.get("shards") != {"N": str(SHARD_COUNT)}:
        return "newer"
    return None


def record_pk(kind: str, record_id: str) -> str:
    return f"{kind}#{record_id}"


def shard_of(pk: str) -> str:
    # A stable hash (not Python's salted hash()): every racer must agree on the shard.
    return str(hashlib.sha256(pk.encode("utf-8")).digest()[0] % SHARD_COUNT)


def push_key(pushed_at_ms: int, record: SyncRecord) -> str:
    return f"{pushed_at_ms:013d}#{record.kind}#{record.record_id}#{record.version:010d}"


def watermark_key(ms: int) -> str:
    """A pushed_key lower bound: every key pushed at or after `ms` sorts above it."""
    return f"{max(ms, 0):013d}"


def record_item(record: SyncRecord, pushed_at_ms: int) -> Item:
    pk = record_pk(record.kind, record.record_id)
    item: Item = {
        PK: {"S": pk},
        "content_hash": {"S": record.content_hash},
        "version": {"N": str(record.version)},
        "body": {"S": record.canonical_body.decode("utf-8")},
        SHARD: {"S": shard_of(pk)},
        PUSHED_KEY: {"S": push_key(pushed_at_ms, record)},
    }
    if record.seal is not None:
        item["signer"] = {"S": record.seal.signer}
        item["signature"] = {"S": record.seal.signature}
    return item


def held_hash_and_version(item: Mapping[str, Any]) -> tuple[str | None, int]:
    """The content hash and version of an existing item, tolerating a malformed one."""
    stated = _string(item, "content_hash")
    try:
        version = _number(item, "version")
    except RecordInvalidError:
        version = -1
    return stated, version


def decode_item(item: Mapping[str, Any]) -> SyncRecord | Quarantined:
    """Validate a pulled item; anything wrong becomes a Quarantined outcome."""
    pk = _string(item, PK) or "?"
    where = f"item {safe_text(pk, 80)}"
    body_text = _string(item, "body")
    raw = body_text if body_text is not None else repr(sorted(item))
    try:
        kind, separator, record_id = pk.partition("#")
        if not separator:
            raise RecordInvalidError("its key is not <kind>#<id>")
        if body_text is None:
            raise RecordInvalidError("it has no body string")
        if len(body_text) > MAX_BODY_BYTES:
            raise RecordInvalidError(f"its body is longer than {MAX_BODY_BYTES} characters")
        body = parse_json(body_text)
        version = _number(item, "version")
    except RecordInvalidError as exc:
        return quarantine(str(exc), where, raw)
    return build_record(
        kind,
        record_id,
        _string(item, "content_hash"),
        body,
        version,
        where=where,
        raw=raw,
        signer=_optional_string(item, "signer"),
        signature=_optional_string(item, "signature"),
    )


def _optional_string(item: Mapping[str, Any], name: str) -> str | None:
    """None when absent; a present attribute that is not a string reads as "" (so the
    seal check refuses it instead of the record passing as unsealed)."""
    if name not in item:
        return None
    return _string(item, name) or ""


def _string(item: Mapping[str, Any], name: str) -> str | None:
    value = item.get(name)
    if isinstance(value, dict) and set(value) == {"S"} and isinstance(value["S"], str):
        return value["S"]
    return None


def _number(item: Mapping[str, Any], name: str) -> int:
    value = item.get(name)
    text = value.get("N") if isinstance(value, dict) and set(value) == {"N"} else None
    if not isinstance(text, str) or not text.isdigit() or len(text) > 10:
        raise RecordInvalidError(f"its {name} is not a whole number")
    number = int(text)
    if number > MAX_VERSION:
        raise RecordInvalidError(f"its {name} is too large")
    return number

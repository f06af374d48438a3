"""Sync: share a league through a store (a shared folder, or DynamoDB + S3 for bundles).

The stores (one contract, protocol.py): create-only, idempotent `push`; cursor-paginated
`pull` of what is new; conflicts reported, never overwritten; bad pulled records
quarantined, never fatal.

    from league.sync import make_record, open_store
    with open_store("dir:/mnt/league") as store:
        store.init()
        report = store.push([make_record("racer", racer_id, {...})])
        page = store.pull(cursor=None)

The league side (engine.py): `sync(league, store, store_key(url))` pushes every shared
row the store lacks and pulls, validates (validate.py) and inserts what is new, keeping
its bookkeeping in local-only tables (local.py). identity.py settles racers and tracks
made on two machines, profiles.py guards renames with versioned profiles, and
bundle_sync.py moves model bundles through S3 (`open_bundle_store("s3://bucket/prefix")`).
boto3 is imported only when a DynamoDB or S3 store is opened.
"""

from league.sync.errors import (
    BundleCorruptError,
    BundleError,
    BundleNotFoundError,
    CursorInvalidError,
    RecordInvalidError,
    StoreAccessDeniedError,
    StoreFolderMissingError,
    StoreIncompatibleError,
    StoreNotInitialisedError,
    StoreUnavailable,
    StoreUrlError,
    SyncError,
)
from league.sync.protocol import (
    Conflict,
    ContentConflict,
    PullPage,
    PushReport,
    RecordRef,
    RecordStore,
    VersionConflict,
)
from league.sync.record import KINDS, VERSIONED_KINDS, Quarantined, SyncRecord, make_record
from league.sync.retry import RetryPolicy
from league.sync.stores import open_bundle_store, open_store
from league.sync.urls import DirUrl, DynamoDbUrl, S3Url, StoreUrl, parse_store_url

__all__ = [
    "KINDS",
    "VERSIONED_KINDS",
    "BundleCorruptError",
    "BundleError",
    "BundleNotFoundError",
    "Conflict",
    "ContentConflict",
    "CursorInvalidError",
    "DirUrl",
    "DynamoDbUrl",
    "PullPage",
    "PushReport",
    "Quarantined",
    "RecordInvalidError",
    "RecordRef",
    "RecordStore",
    "RetryPolicy",
    "S3Url",
    "StoreAccessDeniedError",
    "StoreFolderMissingError",
    "StoreIncompatibleError",
    "StoreNotInitialisedError",
    "StoreUnavailable",
    "StoreUrl",
    "StoreUrlError",
    "SyncError",
    "SyncRecord",
    "VersionConflict",
    "make_record",
    "open_bundle_store",
    "open_store",
    "parse_store_url",
]

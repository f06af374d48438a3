"""Open a store from its URL: the one place that maps URL forms to store classes.

boto3 is imported only when a DynamoDB or S3 store is opened, so commands that never
sync (and the CLI's argument parsing) do not pay for it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from league.sync.dir_store import DirStore
from league.sync.errors import StoreUrlError
from league.sync.protocol import RecordStore
from league.sync.retry import RetryPolicy
from league.sync.urls import DirUrl, DynamoDbUrl, S3Url, StoreUrl, parse_store_url

if TYPE_CHECKING:
    from league.sync.s3_bundles import S3BundleStore


def open_store(url: str | StoreUrl, *, retry: RetryPolicy | None = None) -> RecordStore:
    """The record store for `url` (dir: or dynamodb://); no network traffic until used."""
    parsed = parse_store_url(url) if isinstance(url, str) else url
    if isinstance(parsed, DirUrl):
        return DirStore(parsed.path)
    if isinstance(parsed, DynamoDbUrl):
        from league.sync.dynamodb_store import DynamoDbStore  # noqa: PLC0415 (boto3: only for a DynamoDB store)

        return DynamoDbStore(parsed, retry=retry)
    raise StoreUrlError(
        f"{parsed} holds model bundles, not league records: sync records with a dir: or "
        "dynamodb:// store and give the s3:// URL for bundles"
    )


def open_bundle_store(url: str | StoreUrl, *, retry: RetryPolicy | None = None) -> S3BundleStore:
    """The model-bundle store for an s3:// URL."""
    parsed = parse_store_url(url) if isinstance(url, str) else url
    if not isinstance(parsed, S3Url):
        raise StoreUrlError(f"{parsed} is not an s3://BUCKET/PREFIX URL: bundles live in S3")
    from league.sync.s3_bundles import S3BundleStore  # noqa: PLC0415 (boto3: only for an S3 bundle store)

    return S3BundleStore(parsed, retry=retry)

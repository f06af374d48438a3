"""Model bundles in S3 (`s3://BUCKET/PREFIX[?region=R&endpoint=URL]`), so a league host can
race everyone's models while DynamoDB items stay small.

Keys are content-addressed: `<prefix>/bundles/<sha256>.racer-bundle`. The same bundle is
uploaded once (an existing key is skipped), a key can only ever hold the bytes it is named
after, and a download is size-limited and checked against its hash before it is moved
into place atomically. A bundle holds tensors and JSON only; nothing fetched is executed.

An upload is one PutObject (never a multipart upload), so a killed upload leaves nothing
in the bucket. A killed download leaves its partial file beside the destination; the next
download of that bundle removes those old enough that no download can still be writing.
"""

from __future__ import annotations

import base64
import contextlib
import glob
import hashlib
import os
import re
import tempfile
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, BinaryIO, Final

import botocore.exceptions

from league.sync.aws import AwsCaller, error_code, resolve_region, s3_client
from league.sync.errors import (
    BundleCorruptError,
    BundleError,
    BundleNotFoundError,
    StoreIncompatibleError,
)
from league.sync.retry import RetryPolicy
from league.sync.urls import S3Url

BUNDLE_SUFFIX: Final = ".racer-bundle"
DEFAULT_MAX_BUNDLE_BYTES: Final = 256 * 1024 * 1024
SHA256_PATTERN: Final = re.compile(r"[0-9a-f]{64}")
_CHUNK: Final = 1024 * 1024
# A partial download this old is a killed download's: a live one writes every few seconds.
_DEAD_PART_S: Final = 600.0


@dataclass(frozen=True)
class BundleRef:
    """A bundle in the bucket: its hash (its name), size and key."""

    sha256: str
    size: int
    key: str


class S3BundleStore:
    """Content-addressed model bundles in one S3 bucket under a prefix."""

    def __init__(
        self,
        url: S3Url,
        *,
        retry: RetryPolicy | None = None,
        max_bytes: int = DEFAULT_MAX_BUNDLE_BYTES,
    ) -> None:
        self.url = url
        self.max_bytes = max_bytes
        self.region = resolve_region(url.region, url.endpoint, str(url))
        where = url.endpoint or f"region {self.region}"
        self._call = AwsCaller(
            f"the S3 bucket {url.bucket} ({where})", str(url), retry or RetryPolicy()
        )
        self._client = s3_client(self.region, url.endpoint, self._call.policy, 4)

    @property
    def description(self) -> str:
        return self._call.description

    def __enter__(self) -> S3BundleStore:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        self._client.close()

    def key_for(self, sha256: str) -> str:
        """The object key of a bundle; the hash is validated, never taken on trust."""
        if not SHA256_PATTERN.fullmatch(sha256):
            raise BundleError(f"{sha256[:80]!r} is not a bundle hash (64 lowercase hex digits)")
        name = f"bundles/{sha256}{BUNDLE_SUFFIX}"
        return f"{self.url.prefix}/{name}" if self.url.prefix else name

    def init(self) -> None:
        """Create the bucket if it does not exist yet; idempotent."""
        client = self._client
        arguments: dict[str, Any] = {"Bucket": self.url.bucket}
        if self.region != "us-east-1":  # us-east-1 refuses an explicit location constraint
            arguments["CreateBucketConfiguration"] = {"LocationConstraint": self.region}

        def create() -> None:
            try:
                client.create_bucket(**arguments)
            except client.exceptions.BucketAlreadyOwnedByYou:
                pass
            except client.exceptions.BucketAlreadyExists:
                raise StoreIncompatibleError(
                    f"the bucket name {self.url.bucket} is taken by another AWS account: "
                    "choose another bucket name"
                ) from None

        self._call(create)
        self._call(partial(client.head_bucket, Bucket=self.url.bucket))

    def find(self, sha256: str) -> BundleRef | None:
        """The bundle with this hash, or None if the bucket does not have it."""
        key = self.key_for(sha256)
        response = self._call(partial(self._head, key))
        if response is None:
            return None
        return BundleRef(sha256, int(response.get("ContentLength", 0)), key)

    def put(self, path: Path) -> tuple[BundleRef, bool]:
        """Upload the bundle file at `path` unless the bucket has it; (ref, uploaded)."""
        sha256, size = _hash_file(path)
        if size > self.max_bytes:
            raise BundleError(
                f"{path.name} is {size} bytes, more than the {self.max_bytes}-byte bundle limit"
            )
        existing = self.find(sha256)
        if existing is not None and existing.size == size:
            return existing, False
        key = self.key_for(sha256)
        with path.open("rb") as handle:
            uploaded = self._call(partial(self._put_once, handle, key, sha256, size))
        return BundleRef(sha256, size, key), uploaded

    def fetch(self, sha256: str, destination: Path) -> BundleRef:
        """Download a bundle to `destination`, checking its size and hash; atomic."""
        key = self.key_for(sha256)
        head = self._call(partial(self._head, key))
        if head is None:
            raise BundleNotFoundError(
                f"the bundle {sha256[:12]} is not in {self.description}: ask its racer to sync"
            )
        stated = int(head.get("ContentLength", 0))
        if stated > self.max_bytes:
            raise BundleCorruptError(
                f"the bundle {sha256[:12]} is {stated} bytes, more than the "
                f"{self.max_bytes}-byte limit: it was not downloaded"
            )
        destination.parent.mkdir(parents=True, exist_ok=True)
        _remove_dead_parts(destination)
        fd, temp_name = tempfile.mkstemp(
            prefix=f".{destination.name}.", suffix=".part", dir=destination.parent
        )
        try:
            with os.fdopen(fd, "wb") as out:
                digest, size = self._call(partial(self._download, key, out, stated))
                out.flush()
                os.fsync(out.fileno())
            if digest != sha256:
                raise BundleCorruptError(
                    f"the bundle {sha256[:12]} downloaded from {self.description} does not "
                    f"match its hash (got {digest[:12]}): it was discarded"
                )
            os.replace(temp_name, destination)
        except BaseException:
            Path(temp_name).unlink(missing_ok=True)
            raise
        return BundleRef(sha256, size, key)

    # -- single attempts (each retried as a whole by self._call) -------------------------

    def _head(self, key: str) -> dict[str, Any] | None:
        try:
            return dict(self._client.head_object(Bucket=self.url.bucket, Key=key))
        except botocore.exceptions.ClientError as exc:
            if error_code(exc) in ("404", "NoSuchKey", "NotFound"):
                return None
            raise

    def _put_once(self, handle: BinaryIO, key: str, sha256: str, size: int) -> bool:
        handle.seek(0)
        digest_b64 = base64.b64encode(bytes.fromhex(sha256)).decode("ascii")
        try:
            self._client.put_object(
                Bucket=self.url.bucket,
                Key=key,
                Body=handle,
                ContentLength=size,
                ContentType="application/octet-stream",
                Metadata={"sha256": sha256},
                ChecksumSHA256=digest_b64,  # the server rejects bytes damaged on the way
                IfNoneMatch="*",  # never rewrite a key (same name = same bytes anyway)
            )
        except botocore.exceptions.ClientError as exc:
            if error_code(exc) in ("PreconditionFailed", "412"):
                return False  # another racer uploaded it meanwhile
            raise
        return True

    def _download(self, key: str, out: BinaryIO, stated: int) -> tuple[str, int]:
        out.seek(0)
        out.truncate()
        response = self._client.get_object(Bucket=self.url.bucket, Key=key)
        digest = hashlib.sha256()
        size = 0
        body = response["Body"]
        with contextlib.closing(body):
            for chunk in body.iter_chunks(_CHUNK):
                size += len(chunk)
                if size > min(stated, self.max_bytes):
                    raise BundleCorruptError(
                        f"the bundle at {key} is larger than its stated {stated} bytes: "
                        "it was discarded"
                    )
                digest.update(chunk)
                out.write(chunk)
        return digest.hexdigest(), size


def _remove_dead_parts(destination: Path) -> None:
    """Partial downloads of `destination` left by a download that was killed."""
    cutoff = time.time() - _DEAD_PART_S
    for part in destination.parent.glob(f".{glob.escape(destination.name)}.*.part"):
        with contextlib.suppress(OSError):
            if part.lstat().st_mtime < cutoff:
                part.unlink()


def _hash_file(path: Path) -> tuple[str, int]:
    try:
        digest = hashlib.sha256()
        size = 0
        with path.open("rb") as handle:
            while chunk := handle.read(_CHUNK):
                digest.update(chunk)
                size += len(chunk)
    except OSError as exc:
        raise BundleError(f"cannot read the bundle {path}: {exc.strerror}") from None
    return digest.hexdigest(), size

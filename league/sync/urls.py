"""Store URLs: the one string a league saves to say where it syncs.

    dir:PATH                                   a shared folder
    dynamodb://TABLE?region=R[&endpoint=URL]   a DynamoDB table (endpoint: any compatible server)
    s3://BUCKET/PREFIX[?region=R&endpoint=URL] model bundles in S3

Every part is checked here, so nothing downstream builds an AWS call or a path from an
unchecked string. `str(url)` gives the canonical form to save.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import parse_qsl, urlsplit

from league.sync.errors import StoreUrlError
from league.sync.record import safe_text

ACCEPTED_FORMS = "dir:PATH, dynamodb://TABLE?region=R[&endpoint=URL] or s3://BUCKET/PREFIX[?region=R&endpoint=URL]"
_TABLE = re.compile(r"[A-Za-z0-9_.-]{3,255}")
_BUCKET = re.compile(r"[a-z0-9][a-z0-9.-]{1,61}[a-z0-9]")
_PREFIX_PART = re.compile(r"[A-Za-z0-9_.-]{1,100}")
_REGION = re.compile(r"[a-z]{2}(-[a-z]+)+-\d{1,2}")


@dataclass(frozen=True)
class DirUrl:
    path: Path

    def __str__(self) -> str:
        return f"dir:{self.path}"


@dataclass(frozen=True)
class DynamoDbUrl:
    table: str
    region: str | None = None
    endpoint: str | None = None

    def __str__(self) -> str:
        return f"dynamodb://{self.table}{_query(self.region, self.endpoint)}"


@dataclass(frozen=True)
class S3Url:
    bucket: str
    prefix: str = ""
    region: str | None = None
    endpoint: str | None = None

    def __str__(self) -> str:
        path = f"/{self.prefix}" if self.prefix else ""
        return f"s3://{self.bucket}{path}{_query(self.region, self.endpoint)}"


StoreUrl = DirUrl | DynamoDbUrl | S3Url


def parse_store_url(url: str) -> StoreUrl:
    """Parse and validate a store URL; StoreUrlError names the accepted forms."""
    text = url.strip()
    if text.startswith("dir:"):
        return _parse_dir(text)
    if text.startswith("dynamodb://"):
        return _parse_dynamodb(text)
    if text.startswith("s3://"):
        return _parse_s3(text)
    raise _bad(url, "unknown kind of store")


def _parse_dir(text: str) -> DirUrl:
    raw = text[len("dir:") :]
    if raw.startswith("//"):  # tolerate dir:///abs/path
        raw = raw[2:]
    if not raw or "\x00" in raw:
        raise _bad(text, "the folder path is missing")
    return DirUrl(Path(raw).expanduser().absolute())


def _parse_dynamodb(text: str) -> DynamoDbUrl:
    parts = urlsplit(text)
    table = parts.netloc
    if parts.path not in ("", "/") or parts.fragment:
        raise _bad(text, "a DynamoDB URL has only a table name, then ?region= and &endpoint=")
    if not _TABLE.fullmatch(table):
        raise _bad(text, "a table name is 3-255 letters, digits, '_', '-' or '.'")
    region, endpoint = _parse_query(text, parts.query)
    return DynamoDbUrl(table, region, endpoint)


def _parse_s3(text: str) -> S3Url:
    parts = urlsplit(text)
    if not _BUCKET.fullmatch(parts.netloc) or ".." in parts.netloc:
        raise _bad(text, "a bucket name is 3-63 lowercase letters, digits, '.' or '-'")
    pieces = [piece for piece in parts.path.split("/") if piece]
    if parts.fragment or any(
        not _PREFIX_PART.fullmatch(piece) or piece in (".", "..") for piece in pieces
    ):
        raise _bad(text, "a prefix is folder names of letters, digits, '_', '-' or '.'")
    region, endpoint = _parse_query(text, parts.query)
    return S3Url(parts.netloc, "/".join(pieces), region, endpoint)


def _parse_query(text: str, query: str) -> tuple[str | None, str | None]:
    try:
        pairs = parse_qsl(query, keep_blank_values=True, strict_parsing=bool(query))
    except ValueError:
        raise _bad(text, "the part after '?' is not name=value pairs") from None
    names = [name for name, _ in pairs]
    if any(name not in ("region", "endpoint") for name in names) or len(set(names)) != len(names):
        raise _bad(text, "the only options are region= and endpoint=, each at most once")
    options = dict(pairs)
    region = options.get("region")
    if region is not None and not _REGION.fullmatch(region):
        raise _bad(text, "the region is not like eu-west-1")
    endpoint = options.get("endpoint")
    if endpoint is not None:
        endpoint = _check_endpoint(text, endpoint)
    return region, endpoint


def _check_endpoint(text: str, endpoint: str) -> str:
    parts = urlsplit(endpoint)
    try:
        port_ok = parts.port is None or 0 < parts.port < 65536
    except ValueError:
        port_ok = False
    if (
        parts.scheme not in ("http", "https")
        or not parts.hostname
        or not port_ok
        or parts.query
        or parts.fragment
        or parts.username
    ):
        raise _bad(text, "the endpoint is not like http://HOST:PORT")
    return endpoint.rstrip("/")


def _query(region: str | None, endpoint: str | None) -> str:
    options = [f"region={region}"] if region else []
    if endpoint:
        options.append(f"endpoint={endpoint}")
    return "?" + "&".join(options) if options else ""


def _bad(url: str, reason: str) -> StoreUrlError:
    return StoreUrlError(
        f"{safe_text(url, 200)!r} is not a store URL ({reason}): use {ACCEPTED_FORMS}"
    )

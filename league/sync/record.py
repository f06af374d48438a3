"""The shared record: what every store holds, and the rules every record must pass.

A record is immutable once shared: `(kind, record_id)` names it, `content_hash` says
what it holds, and its `seal` says who made it (an Ed25519 signature over kind, id,
version and hash: league.trust.seals). Only `racer_profile` records (a racer's editable
display fields) change, and each change is a new `version` written with a conditional write.

Everything pulled from a store is untrusted. `decode_envelope` checks the kind against a
fixed list, the id's form (ids later become file names and keys), JSON-only types,
nesting depth, string and total sizes, that the hash matches the body, and that a seal
has the form of one, and turns anything wrong into a `Quarantined` outcome instead of an
exception, so one bad record never stops the rest of a sync. Whether the seal's signature
is genuine, and whether its signer may make the record, is the pull's business (stores
carry seals without judging them).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Final

from league.sync.errors import RecordInvalidError
from sim.foundation.ids import canonical_json, is_valid_id

# The fixed list of what may be shared. Nothing else is ever accepted from a store.
# One kind per shared league table (league.sync.kinds maps them), then the sync-level
# kinds: a racer's versioned profile and the map from a model to its bundle in S3.
KINDS: Final = (
    "racer",
    "track",
    "season",
    "night",
    "entrant",
    "heat",
    "night_closure",
    "night_change",
    "bracket",
    "head_to_head",
    "submission",
    "race",
    "correction",
    "racer_profile",
    "bundle",
    "roster",
    "model",
)
# Kinds whose records change through numbered versions; every other kind is immutable.
VERSIONED_KINDS: Final = frozenset({"racer_profile"})

# Limits: well under DynamoDB's 400 KB item limit, and small enough that a hostile store
# cannot make a puller allocate much or recurse deeply.
MAX_BODY_BYTES: Final = 256 * 1024
MAX_ENVELOPE_BYTES: Final = MAX_BODY_BYTES + 4096
MAX_DEPTH: Final = 16
MAX_STRING_CHARS: Final = 32 * 1024
MAX_KEY_CHARS: Final = 128
MAX_VERSION: Final = 1_000_000_000
_INT_RANGE: Final = (-(2**63), 2**63 - 1)  # what SQLite can store
# Format 2 added the seal; format 1 files (written before records were signed) still read,
# as records without a seal.
ENVELOPE_FORMAT: Final = 2
_UNSEALED_FORMAT: Final = 1

HASH_PATTERN: Final = re.compile(r"[0-9a-f]{64}")
# C0/C1 control characters (except tab, newline, carriage return) can drive a terminal;
# lone surrogates cannot be encoded. Neither has any business in league data.
_FORBIDDEN_CHARS: Final = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f\ud800-\udfff]")
_EXCERPT_CHARS: Final = 120

JsonValue = None | bool | int | float | str | list["JsonValue"] | dict[str, "JsonValue"]
_HEX_PUBLIC: Final = re.compile(r"[0-9a-f]{64}")
_HEX_SIGNATURE: Final = re.compile(r"[0-9a-f]{128}")


@dataclass(frozen=True)
class Seal:
    """Who signed a record: their public key and the signature, both lowercase hex.
    Construction checks the form only; league.trust.seals checks the signature."""

    signer: str
    signature: str

    def __post_init__(self) -> None:
        if not isinstance(self.signer, str) or not _HEX_PUBLIC.fullmatch(self.signer):
            raise RecordInvalidError("its signer is not a public key (64 lowercase hex digits)")
        if not isinstance(self.signature, str) or not _HEX_SIGNATURE.fullmatch(self.signature):
            raise RecordInvalidError("its signature is not 128 lowercase hex digits")


@dataclass(frozen=True)
class SyncRecord:
    """One shared record. Construction validates everything, including the hash.

    `body` is a plain JSON object; treat it as read-only (its hash is fixed at creation).
    """

    kind: str
    record_id: str
    content_hash: str
    body: dict[str, Any] = field(repr=False)
    version: int = 0
    # Who signed it; None for a record made here and not yet pushed, or an unsigned one
    # pulled (which the pull refuses). Not part of what the record is, so not compared.
    seal: Seal | None = field(default=None, compare=False, repr=False)
    # The body's canonical JSON, which the hash is taken over: computed once here, and
    # reused by the stores (encoding it again for every write is a push's main CPU cost).
    canonical_body: bytes = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        _check_kind_id_version(self.kind, self.record_id, self.version)
        if not isinstance(self.content_hash, str) or not HASH_PATTERN.fullmatch(self.content_hash):
            raise RecordInvalidError("the content hash is not 64 lowercase hex digits")
        canonical = validate_body(self.body)
        object.__setattr__(self, "canonical_body", canonical)
        actual = hashlib.sha256(canonical).hexdigest()
        if actual != self.content_hash:
            raise RecordInvalidError(
                f"the content hash does not match the body (stated {self.content_hash[:12]}…, "
                f"actual {actual[:12]}…)"
            )

    @property
    def key(self) -> tuple[str, str]:
        """What names the record in every store: the same key never holds two contents."""
        return (self.kind, self.record_id)

    def sealed(self, seal: Seal | None) -> SyncRecord:
        """The same record carrying `seal` (the body is shared, not copied or re-checked)."""
        twin = copy.copy(self)  # no __init__: the body was checked when self was made
        object.__setattr__(twin, "seal", seal)
        return twin


def make_record(kind: str, record_id: str, body: Mapping[str, Any], version: int = 0) -> SyncRecord:
    """Build a record from local data, computing its content hash."""
    plain = dict(body)
    digest = hashlib.sha256(validate_body(plain)).hexdigest()
    return SyncRecord(kind, record_id, digest, plain, version)  # validates the rest


@dataclass(frozen=True)
class Quarantined:
    """A record pulled from a store that failed validation; it never reaches the league.

    `where` names its place in the store (a file or a key), `excerpt` is the start of
    what was there. Both are plain text from an untrusted source: display them as
    plain text (rich.text.Text), never as markup.
    """

    reason: str
    where: str
    excerpt: str
    # Not even a whole JSON document: what a file still being written looks like.
    partial: bool = False


def validate_body(body: object) -> bytes:
    """Check that `body` is a JSON object within the limits; returns its canonical JSON."""
    if not isinstance(body, dict):
        raise RecordInvalidError("the record body is not a JSON object")
    _check_value(body, depth=1)
    try:
        canonical = canonical_json(body)
    except (ValueError, TypeError) as exc:  # NaN/inf slipped through, or a non-JSON type
        raise RecordInvalidError(f"the record body is not plain JSON ({exc})") from None
    size = len(canonical)
    if size > MAX_BODY_BYTES:
        raise RecordInvalidError(
            f"the record body is {size} bytes, more than the {MAX_BODY_BYTES}-byte limit"
        )
    return canonical


def encode_envelope(record: SyncRecord) -> bytes:
    """The bytes a file-based store holds for `record`: the canonical JSON of the envelope
    {body, content_hash, format, id, kind, signature, signer, version} (keys sorted, so
    deterministic; signer and signature null when unsealed), built around the record's
    canonical body rather than encoding the body again."""
    seal = record.seal
    rest = canonical_json(
        {
            "content_hash": record.content_hash,
            "format": ENVELOPE_FORMAT,
            "id": record.record_id,
            "kind": record.kind,
            "signature": None if seal is None else seal.signature,
            "signer": None if seal is None else seal.signer,
            "version": record.version,
        }
    )
    return b'{"body":' + record.canonical_body + b"," + rest[1:]


_UNSEALED_KEYS: Final = frozenset({"format", "kind", "id", "content_hash", "version", "body"})
_ENVELOPE_KEYS: Final = _UNSEALED_KEYS | {"signer", "signature"}


def decode_envelope(raw: bytes, where: str) -> SyncRecord | Quarantined:
    """Parse and validate what a file-based store held; never raises for bad content."""
    if len(raw) > MAX_ENVELOPE_BYTES:
        return quarantine(
            f"it is {len(raw)} bytes, more than the {MAX_ENVELOPE_BYTES}-byte limit", where, raw
        )
    try:
        data = parse_json(raw)
    except RecordInvalidError as exc:
        return replace(quarantine(str(exc), where, raw), partial=True)
    if not isinstance(data, dict):
        return quarantine("it is not a JSON object", where, raw)
    expected = {ENVELOPE_FORMAT: _ENVELOPE_KEYS, _UNSEALED_FORMAT: _UNSEALED_KEYS}
    stated_format = data.get("format")
    fields = None
    if isinstance(stated_format, int) and not isinstance(stated_format, bool):
        fields = expected.get(stated_format)
    if fields is None:
        return quarantine(
            f"its format {safe_text(str(data.get('format')), 20)} is not {ENVELOPE_FORMAT} "
            "(written by another program or a newer racer-tui)",
            where,
            raw,
        )
    if set(data) != fields:
        return quarantine("its fields are not the record fields", where, raw)
    return build_record(
        data["kind"],
        data["id"],
        data["content_hash"],
        data["body"],
        data["version"],
        where=where,
        raw=raw,
        signer=data.get("signer"),
        signature=data.get("signature"),
    )


def build_record(
    kind: object,
    record_id: object,
    stated_hash: object,
    body: object,
    version: object,
    *,
    where: str,
    raw: bytes | str,
    signer: object = None,
    signature: object = None,
) -> SyncRecord | Quarantined:
    """A validated record from untrusted parts, or the reason it was refused. A record
    with neither signer nor signature is unsealed; one with only one of them is refused."""
    try:
        seal = None
        if signer is not None or signature is not None:
            seal = Seal(signer, signature)  # type: ignore[arg-type]  # checked inside
        if not isinstance(kind, str) or not isinstance(record_id, str):
            raise RecordInvalidError("its kind or id is not a string")
        if not isinstance(stated_hash, str):
            raise RecordInvalidError("its content hash is not a string")
        if not isinstance(version, int) or isinstance(version, bool):
            raise RecordInvalidError("its version is not an integer")
        if not isinstance(body, dict):
            raise RecordInvalidError("its body is not a JSON object")
        return SyncRecord(kind, record_id, stated_hash, body, version, seal)
    except RecordInvalidError as exc:
        return quarantine(str(exc), where, raw)


def parse_json(raw: bytes | str) -> Any:
    """json.loads that refuses NaN/Infinity and survives hostile nesting."""
    try:
        text = raw.decode("utf-8") if isinstance(raw, bytes) else raw
        return json.loads(text, parse_constant=_refuse_constant)
    except UnicodeDecodeError:
        raise RecordInvalidError("it is not UTF-8 text") from None
    except RecursionError:
        raise RecordInvalidError("it is nested too deeply") from None
    except ValueError as exc:  # JSONDecodeError, huge integers, NaN/Infinity
        raise RecordInvalidError(f"it is not valid JSON ({exc})") from None


def quarantine(reason: str, where: str, raw: bytes | str) -> Quarantined:
    return Quarantined(reason=reason, where=safe_text(where), excerpt=safe_text(raw))


def safe_text(raw: bytes | str, limit: int = _EXCERPT_CHARS) -> str:
    """A short, printable excerpt of untrusted bytes: control characters become '?'."""
    text = raw[: limit * 4].decode("utf-8", "replace") if isinstance(raw, bytes) else raw
    clipped = text[:limit]
    cleaned = "".join(char if char.isprintable() else "?" for char in clipped)
    return cleaned + ("…" if len(text) > limit else "")


def _refuse_constant(name: str) -> None:
    raise ValueError(f"{name} is not allowed")


def _check_kind_id_version(kind: object, record_id: object, version: object) -> None:
    if kind not in KINDS:
        raise RecordInvalidError(f"its kind {safe_text(str(kind), 40)!r} is not a shared kind")
    if not is_valid_id(record_id):
        raise RecordInvalidError(f"its id {safe_text(str(record_id), 40)!r} is not a valid id")
    if not isinstance(version, int) or isinstance(version, bool):
        raise RecordInvalidError("its version is not an integer")
    if kind in VERSIONED_KINDS:
        if not 1 <= version <= MAX_VERSION:
            raise RecordInvalidError(f"a {kind} record needs a version from 1 to {MAX_VERSION}")
    elif version != 0:
        raise RecordInvalidError(f"a {kind} record is immutable, so its version must be 0")


def _check_value(value: object, depth: int) -> None:
    if depth > MAX_DEPTH:
        raise RecordInvalidError(f"the record body is nested more than {MAX_DEPTH} levels deep")
    if value is None or isinstance(value, bool):
        return
    if isinstance(value, int):
        if not _INT_RANGE[0] <= value <= _INT_RANGE[1]:
            raise RecordInvalidError("the record body has an integer outside the 64-bit range")
    elif isinstance(value, float):
        if not math.isfinite(value):
            raise RecordInvalidError("the record body has a NaN or infinite number")
    elif isinstance(value, str):
        _check_string(value, MAX_STRING_CHARS, "string")
    elif isinstance(value, list):
        for item in value:
            _check_value(item, depth + 1)
    elif isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                raise RecordInvalidError("the record body has a non-string object key")
            _check_string(key, MAX_KEY_CHARS, "object key")
            _check_value(item, depth + 1)
    else:
        raise RecordInvalidError(
            f"the record body holds a {type(value).__name__}, which is not JSON"
        )


def _check_string(text: str, limit: int, what: str) -> None:
    if len(text) > limit:
        raise RecordInvalidError(f"the record body has a {what} longer than {limit} characters")
    if _FORBIDDEN_CHARS.search(text):
        raise RecordInvalidError(f"the record body has a {what} with control characters")

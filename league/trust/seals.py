"""The signature on one shared record.

A seal signs the record's kind, id, version and content hash (the SHA-256 of its
canonical body), so it covers the body without hashing it again, and it cannot be moved
to another record, another version of the same record, or another kind. The message
starts with a fixed label so a racer-tui signature can never be mistaken for a signature
on anything else.
"""

from __future__ import annotations

from typing import Final

from league.sync.record import Seal, SyncRecord
from league.trust.keys import SigningKey, verify

_LABEL: Final = b"racer-tui record seal 1\x00"


def seal_message(kind: str, record_id: str, version: int, content_hash: str) -> bytes:
    fields = (kind, record_id, str(version), content_hash)
    return _LABEL + b"\x00".join(field.encode("ascii") for field in fields)


def make_seal(record: SyncRecord, key: SigningKey) -> Seal:
    message = seal_message(record.kind, record.record_id, record.version, record.content_hash)
    return Seal(key.public_hex, key.sign(message))


def is_genuine(record: SyncRecord) -> bool:
    """Whether the record carries a seal whose signature matches its content."""
    if record.seal is None:
        return False
    message = seal_message(record.kind, record.record_id, record.version, record.content_hash)
    return verify(record.seal.signer, message, record.seal.signature)

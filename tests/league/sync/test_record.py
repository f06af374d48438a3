"""The shared-record rules: what may be built locally, and what a pull quarantines."""

from __future__ import annotations

import json
from typing import Any

import pytest

from league.sync.errors import RecordInvalidError
from league.sync.record import (
    MAX_BODY_BYTES,
    Quarantined,
    SyncRecord,
    decode_envelope,
    encode_envelope,
    make_record,
)
from sim.foundation.ids import canonical_json, content_hash, new_id
from tests.league.sync.records import submission


def test_a_record_round_trips_through_its_envelope() -> None:
    record = submission(1)
    decoded = decode_envelope(encode_envelope(record), "here")
    assert decoded == record
    assert record.content_hash == content_hash(record.body)


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        ({"lap": float("nan")}, "NaN"),
        ({"lap": float("inf")}, "NaN or infinite"),
        ({"big": 2**70}, "64-bit"),
        ({"name": "a\x1b[2Jb"}, "control characters"),
        ({"name": "x" * 40_000}, "longer than"),
        ({"k" * 200: 1}, "object key longer"),
        ({"set": {1, 2}}, "not JSON"),
        ({"deep": json.loads("[" * 30 + "]" * 30)}, "nested more than"),
        ({"blob": ["x" * 30_000] * 10}, "byte limit"),
    ],
)
def test_bodies_outside_the_rules_are_refused(body: dict[str, Any], reason: str) -> None:
    with pytest.raises(RecordInvalidError, match=reason):
        make_record("submission", new_id(), body)


@pytest.mark.parametrize(
    ("kind", "record_id", "version", "reason"),
    [
        ("reward_function", None, 0, "not a shared kind"),
        ("submission", "../../etc/passwd", 0, "not a valid id"),
        ("submission", None, 1, "immutable"),
        ("racer_profile", None, 0, "version from 1"),
    ],
)
def test_kind_id_and_version_are_checked(
    kind: str, record_id: str | None, version: int, reason: str
) -> None:
    with pytest.raises(RecordInvalidError, match=reason):
        make_record(kind, record_id or new_id(), {"x": 1}, version)


def test_a_stated_hash_that_does_not_match_is_refused() -> None:
    with pytest.raises(RecordInvalidError, match="does not match"):
        SyncRecord("racer", new_id(), "0" * 64, {"name": "Ada"})


def _envelope(**changes: Any) -> bytes:
    record = submission(3)
    data: dict[str, Any] = {
        "format": 1,
        "kind": record.kind,
        "id": record.record_id,
        "content_hash": record.content_hash,
        "version": 0,
        "body": record.body,
    }
    data.update(changes)
    return canonical_json(data)


@pytest.mark.parametrize(
    ("raw", "reason"),
    [
        (b"\xff\xfe not text", "not UTF-8"),
        (b'{"format": 1, "kind": ', "not valid JSON"),
        (b"[" * 100_000, "nested too deeply"),
        (b'{"lap": NaN}', "not valid JSON"),
        (b"[]", "not a JSON object"),
        (_envelope(format=3), "newer racer-tui"),
        (_envelope(format=2), "fields"),  # format 2 has a seal's fields
        (_envelope(signer="ab" * 32), "fields"),  # a seal in a format 1 envelope
        (_envelope(extra=1), "fields"),
        (_envelope(content_hash="a" * 64), "does not match"),
        (_envelope(kind="script"), "not a shared kind"),
        (_envelope(version=True), "not an integer"),
        (_envelope(body={"name": "\x07bell"}), "control characters"),
        (b" " * (MAX_BODY_BYTES + 5000), "limit"),
    ],
)
def test_bad_pulled_bytes_are_quarantined_not_raised(raw: bytes, reason: str) -> None:
    outcome = decode_envelope(raw, "records/submission/x.json")
    assert isinstance(outcome, Quarantined)
    assert reason in outcome.reason
    assert outcome.where == "records/submission/x.json"
    assert all(char.isprintable() for char in outcome.excerpt)
    assert len(outcome.excerpt) <= 121


def test_an_excerpt_never_carries_terminal_control_codes() -> None:
    outcome = decode_envelope(b"\x1b[31m\x1b]0;pwned\x07" + b"x" * 500, "f")
    assert isinstance(outcome, Quarantined)
    assert "\x1b" not in outcome.excerpt and "\x07" not in outcome.excerpt
    assert outcome.excerpt.endswith("…")

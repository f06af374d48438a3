"""Deterministic records for the sync tests (the same ids in every process)."""

from __future__ import annotations

from typing import Any

from league.sync.record import SyncRecord, make_record

_CROCKFORD = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"
BASE_MS = 1_790_000_000_000  # a fixed creation time, late 2026


def fixed_id(ms: int, serial: int) -> str:
    """A valid, time-sortable id made from a millisecond time and a serial number."""
    value = (ms << 80) | serial
    return "".join(_CROCKFORD[(value >> shift) & 31] for shift in range(125, -1, -5))


def submission(serial: int, *, ms: int = BASE_MS, racer: str = "Ada", **extra: Any) -> SyncRecord:
    body: dict[str, Any] = {
        "racer": racer,
        "track": "speedway",
        "best_lap_s": 9.5 + serial / 1000,
        "laps": [{"lap": n, "time_s": 10.0 + n / 10, "off_tracks": n % 2} for n in range(3)],
        **extra,
    }
    return make_record("submission", fixed_id(ms, serial), body)


def submissions(count: int, *, start: int = 0, ms: int = BASE_MS) -> list[SyncRecord]:
    return [submission(serial, ms=ms) for serial in range(start, start + count)]


def profile(serial: int, version: int, display_name: str) -> SyncRecord:
    return make_record(
        "racer_profile", fixed_id(BASE_MS, serial), {"display_name": display_name}, version
    )


def keys(records: list[SyncRecord]) -> list[tuple[str, str, int]]:
    return sorted((record.kind, record.record_id, record.version) for record in records)

"""Counts in words: "1 row", "2 rows", never "1 rows"."""

from __future__ import annotations


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """`count` and the noun in the right number ("1 lap", "3 laps", "1 entry", "2 entries")."""
    word = noun if count == 1 else (plural or f"{noun}s")
    return f"{count:,} {word}"

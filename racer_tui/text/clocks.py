"""The race clock as both front ends write it."""

from __future__ import annotations


def clock_text(seconds: float) -> str:
    """m:ss.mmm: lap times and moments on the race clock."""
    minutes, rest = divmod(max(seconds, 0.0), 60.0)
    return f"{int(minutes)}:{rest:06.3f}"


def elapsed_text(seconds: float) -> str:
    """m:ss, whole seconds gone (a running clock: 74.9 s is 1:14)."""
    minutes, rest = divmod(int(max(seconds, 0.0)), 60)
    return f"{minutes}:{rest:02d}"

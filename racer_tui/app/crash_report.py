"""A crash is never silent: what the app writes, says and leaves behind on an unexpected error.

Textual restores the terminal and prints the traceback when an error escapes a handler;
the app then exited with status 0, and keys still waiting in the terminal went to the shell
(issue 42: a crash in a key burst re-ran `make run`). On such an error the app writes a
report beside the data (`crashes/<time>.txt`: the traceback, the screen as it was, the
versions and the last keys), says where in one sentence once the terminal is back, throws
away the keys typed for the app that it never read, and exits non-zero.
"""

from __future__ import annotations

import platform
import sys
import termios
import traceback
from collections import deque
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import TextIO

from sim.foundation.atomic import write_text_atomic
from sim.foundation.home import data_home

CRASHES_DIR = "crashes"
KEYS_KEPT = 40  # the last keys a report lists: enough to replay the burst that crashed
EXIT_CRASH = 1  # Textual's own return code for an unhandled error


class RecentKeys:
    """The last keys and pastes the app received, oldest first, for a crash report."""

    def __init__(self, size: int = KEYS_KEPT) -> None:
        self._keys: deque[str] = deque(maxlen=size)

    def key(self, key: str) -> None:
        self._keys.append(key)

    def paste(self, text: str) -> None:
        self._keys.append(f"<paste of {len(text)} characters>")

    def listed(self) -> list[str]:
        return list(self._keys)


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "unknown"


def versions() -> str:
    return (
        f"racer-tui {_version('racer-tui')}, textual {_version('textual')}, "
        f"python {platform.python_version()} on {platform.system()} {platform.machine()}"
    )


def report_text(
    error: BaseException, *, screen: str, screen_text: str, keys: list[str], when: datetime
) -> str:
    """The report: what a bug report needs, readable as it is."""
    trace = "".join(traceback.format_exception(type(error), error, error.__traceback__))
    return "\n".join(
        [
            f"racer-tui crash report, {when.isoformat(timespec='seconds')}",
            f"Versions: {versions()}",
            f"Screen: {screen}",
            "",
            f"Last keys (oldest first): {' '.join(keys) if keys else '(none)'}",
            "",
            "Traceback:",
            trace.rstrip(),
            "",
            "The screen as it was:",
            screen_text.rstrip() or "(could not be read)",
            "",
        ]
    )


def write_report(text: str, when: datetime, home: Path | None = None) -> Path:
    """Write the report into the data folder's crashes/ folder; the path it went to."""
    folder = (home if home is not None else data_home()) / CRASHES_DIR
    stamp = when.strftime("%Y%m%d-%H%M%S")
    path = folder / f"{stamp}.txt"
    number = 1
    while path.exists():  # two crashes in a second (tests, a quick restart) keep both
        number += 1
        path = folder / f"{stamp}-{number}.txt"
    write_text_atomic(path, text)
    return path


def now() -> datetime:
    return datetime.now(UTC)


def crash_sentence(report: Path | None, problem: str | None = None) -> str:
    """The one sentence said on stderr once the terminal is back."""
    if report is not None:
        return (
            f"racer-tui stopped on an unexpected error; the report (traceback, screen, "
            f"versions, last keys) is in {report}: please attach it to a bug report."
        )
    reason = f" ({problem})" if problem else ""
    return (
        f"racer-tui stopped on an unexpected error and could not write its report{reason}; "
        "the traceback is above: please copy it into a bug report."
    )


def drop_unread_keys(stream: TextIO | None = None) -> None:
    """Throw away what was typed for the app and never read, so that it cannot run in the
    shell once the app has gone (a burst of keys after a crash is meant for the app)."""
    stream = sys.stdin if stream is None else stream
    try:
        if stream is not None and stream.isatty():
            termios.tcflush(stream.fileno(), termios.TCIFLUSH)
    except (OSError, ValueError, termios.error):
        pass  # not a terminal after all, or closed: nothing waits there


def say_crash(report: Path | None, problem: str | None, stream: TextIO | None = None) -> None:
    out = sys.stderr if stream is None else stream
    print(crash_sentence(report, problem), file=out)
    out.flush()

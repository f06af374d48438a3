"""An automatic timer's lap triggers: text lines on a serial device or a named pipe
(`racer-tui --timer PATH`). A line `lap` is the car crossing the line, `reset` a car reset;
blank lines and `#` comments are skipped. The moment of a trigger is when its line
arrived, taken where it is read, so a busy app does not lengthen the lap.
"""

from __future__ import annotations

import os
import select
import stat
import threading
import time
from collections.abc import Callable, Iterator
from enum import StrEnum
from pathlib import Path

from sim.foundation.remedies import RemedyError

TIMER_ENV = "RACER_TUI_TIMER"  # the timer's path for the app, set by `racer-tui --timer PATH`
POLL_SECONDS = 0.2  # how soon a stopped feed notices it has been stopped
MAX_LINE = 200  # longer is not a timer talking: the rest of the line is dropped


class Trigger(StrEnum):
    LAP = "lap"
    RESET = "reset"


class FeedError(RemedyError):
    """A timer path that cannot be read, or a line that is not a trigger."""


def parse_trigger(line: str) -> Trigger | None:
    """The trigger a line holds; None for a blank line or a comment."""
    word = line.strip().casefold()
    if not word or word.startswith("#"):
        return None
    try:
        return Trigger(word)
    except ValueError:
        shown = line.strip()[:40]
        raise FeedError(f"The timer sent {shown!r}, which is neither 'lap' nor 'reset'.") from None


def check_timer_path(path: str) -> str | None:
    """What is wrong with `path` as a timer feed, or None."""
    try:
        mode = Path(path).stat().st_mode
    except OSError as error:
        return f"The timer {path} cannot be found ({error.strerror}); check the path."
    if not (stat.S_ISFIFO(mode) or stat.S_ISCHR(mode)):
        return f"The timer {path} is neither a serial device nor a named pipe."
    if not os.access(path, os.R_OK):
        return f"The timer {path} cannot be read; check its permissions."
    return None


def follow(
    path: str, stop: threading.Event, clock: Callable[[], float] = time.monotonic
) -> Iterator[tuple[float, str]]:
    """Each line the timer sends, with the moment it arrived, until `stop` is set. A named
    pipe whose writer goes away is waited on for the next one."""
    problem = check_timer_path(path)
    if problem is not None:
        raise FeedError(problem)
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
    pending = b""
    try:
        while not stop.is_set():
            ready, _, _ = select.select([descriptor], [], [], POLL_SECONDS)
            if not ready:
                continue
            try:
                chunk = os.read(descriptor, 4096)
            except BlockingIOError:
                continue
            if not chunk:  # a pipe with no writer now: wait for the next one
                stop.wait(POLL_SECONDS)
                continue
            moment = clock()
            pending += chunk.replace(b"\r", b"\n")
            *lines, pending = pending.split(b"\n")
            pending = pending[-MAX_LINE:]
            for raw in lines:
                text = raw[:MAX_LINE].decode("utf-8", errors="replace")
                if text.strip():
                    yield moment, text
    finally:
        os.close(descriptor)

"""One status model for every long job the app runs (an evaluation, a sync, an import):
what it is doing, since when, how far it has got, and how it ended, with the error in the
racer's words and the key that fixes it.

A screen that runs a job keeps its `Job` and hands every change to a `JobLine`, which is
the only thing that draws it; so a job never shows "done" while it fails again, nor a
spinner after it stopped. `Job` knows nothing of Textual, so tests check it directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import StrEnum


class JobState(StrEnum):
    IDLE = "idle"
    RUNNING = "running"
    DONE = "done"
    FAILED = "failed"
    STOPPED = "stopped"  # by the racer


@dataclass(frozen=True)
class Job:
    """A job's status at one moment. Times are seconds on the app's clock (time.monotonic
    for the ETA, wall time for what is shown: `at` is wall time)."""

    what: str = ""  # "Evaluating ada (3 trials)"
    state: JobState = JobState.IDLE
    at: float = 0.0  # wall time of the last change of state
    started: float = 0.0  # monotonic time it started running
    done: float = 0.0
    total: float | None = None  # None: no known end (the bar pulses)
    outcome: str = ""  # DONE: what it produced; FAILED: the error in the racer's words
    fix: str = ""  # FAILED: what fixes it in the app ("press ctrl+e to try again")

    def running(self, what: str, *, total: float | None, now: float, wall: float) -> Job:
        return Job(what, JobState.RUNNING, wall, now, 0.0, total)

    def doing(self, what: str) -> Job:
        """The same run at another stage ("Pushing 3/10 records")."""
        return replace(self, what=what)

    def progressed(self, done: float, total: float | None) -> Job:
        """Progress with its own total (None: not known), as a new stage reports it."""
        return replace(self, done=done, total=total)

    def advanced(self, done: float, total: float | None = None) -> Job:
        return replace(self, done=done, total=self.total if total is None else total)

    def finished(self, outcome: str, *, wall: float) -> Job:
        done = self.total if self.total is not None else self.done
        return replace(self, state=JobState.DONE, at=wall, done=done, outcome=outcome)

    def failed(self, error: str, fix: str, *, wall: float) -> Job:
        return replace(self, state=JobState.FAILED, at=wall, outcome=error, fix=fix)

    def stopped(self, *, wall: float) -> Job:
        return replace(self, state=JobState.STOPPED, at=wall, outcome="")

    @property
    def fraction(self) -> float | None:
        """How far it has got, 0..1, when its end is known."""
        if self.total is None or self.total <= 0:
            return None
        return min(max(self.done / self.total, 0.0), 1.0)

    def seconds_left(self, now: float) -> float | None:
        """At the pace so far; None until there is a pace to go by."""
        fraction = self.fraction
        if self.state is not JobState.RUNNING or not fraction:
            return None
        elapsed = now - self.started
        left = elapsed * (1.0 - fraction) / fraction
        return left if math.isfinite(left) else None


def sentence(text: str) -> str:
    """A library's or a job's message as a sentence: capital first, full stop last."""
    text = text.strip()
    text = text[:1].upper() + text[1:]
    return text if not text or text.endswith((".", "!", "?")) else text + "."

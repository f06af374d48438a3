"""A time limit on every call of a racer's reward function (and on loading its file).

A reward function is the racer's own Python; one that loops forever or waits on something
that never comes would hang a training, a `reward check` or a league night. A process
that runs racer code installs a `CallLimit` once, from its main thread; from then on each
call `sim.reward_function` makes is timed by a watchdog thread, which interrupts the main
thread with a signal when a call runs longer than the limit. The interrupted call raises
`RewardTimeout` from inside the racer's code, so the error names the line it was running.

The cost on the hot path (about 30,000 calls a second in training) is two clock reads and
two attribute writes per call; the watchdog wakes a few times per limit. A function that
blocks signals or spins inside C code cannot be interrupted this way: the processes that
run racer code are children with a hard deadline of their own (see `sim.reward_probe` and
the training launcher), so nothing hangs for good.
"""

from __future__ import annotations

import signal
import threading
import time
from types import FrameType

DEFAULT_SECONDS = 1.0  # DeepRacer gives a step 1/15 s; a second is generous and still short
# How often the watchdog looks, as a share of the limit: a call is stopped at most a
# quarter of the limit late.
LOOKS_PER_LIMIT = 4


class RewardTimeout(BaseException):
    """Raised inside a reward call that ran over its limit. A BaseException, so a racer's
    `except Exception:` cannot swallow it."""

    def __init__(self, seconds: float) -> None:
        super().__init__(f"did not return within {seconds:g} s")
        self.seconds = seconds


class CallLimit:
    """Times calls marked with `begin()` / `end()`; see the module docstring."""

    def __init__(self, seconds: float) -> None:
        if not seconds > 0:
            raise ValueError("a reward time limit must be a positive number of seconds")
        self.seconds = seconds
        self.started = 0.0  # monotonic time the current call began; 0: no call running
        self._fired = 0.0  # the call the watchdog has interrupted
        self._main = threading.main_thread().ident

    def begin(self) -> None:
        self.started = time.monotonic()

    def end(self) -> None:
        self.started = 0.0

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        del signum, frame
        if self.started and self.started == self._fired:
            self.started = 0.0
            raise RewardTimeout(self.seconds)

    def _watch(self) -> None:
        pause = self.seconds / LOOKS_PER_LIMIT
        while True:
            time.sleep(pause)
            began = self.started
            if began and began != self._fired and time.monotonic() - began > self.seconds:
                self._fired = began
                if self._main is not None:
                    signal.pthread_kill(self._main, signal.SIGALRM)


_ACTIVE: CallLimit | None = None


def install(seconds: float = DEFAULT_SECONDS) -> CallLimit:
    """Limit every reward call in this process to `seconds` (from the main thread, once;
    a second call changes the limit)."""
    # A module global, not a registry object: the hot path reads one module attribute.
    global _ACTIVE  # noqa: PLW0603
    if _ACTIVE is not None:
        _ACTIVE.seconds = seconds
        return _ACTIVE
    limit = CallLimit(seconds)
    signal.signal(signal.SIGALRM, limit._on_signal)
    threading.Thread(target=limit._watch, name="reward-call-limit", daemon=True).start()
    _ACTIVE = limit
    return limit


def active() -> CallLimit | None:
    """The limit installed in this process, if any."""
    return _ACTIVE

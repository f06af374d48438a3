"""A time limit on every call of a racer's reward function (and on loading its file).

A reward function is the racer's own Python; one that loops forever or waits on something
that never comes would hang a training, a `reward check` or a league night. A process
that runs racer code installs a `CallLimit` once, from its main thread; from then on each
call `sim.reward.function` makes is timed by a watchdog thread, which interrupts the main
thread with a signal when a call runs longer than the limit. The interrupted call raises
`RewardTimeout` from inside the racer's code, so the error names the line it was running.

The cost on the hot path (about 30,000 calls a second in training) is one clock read and
a few attribute reads and writes per call (about 300 ns); the watchdog wakes a few times
per limit. A call that swallows the interruption (`except:`) is interrupted again at every
look and failed when it returns; one still running STUCK_AFTER_LIMITS limits on, or that
blocks signals or spins inside C code, ends its process through `on_stuck`; and the
processes that run racer code are children with a hard deadline of their own (see
`sim.reward.probe` and the training launcher), so nothing hangs for good.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable
from types import FrameType

DEFAULT_SECONDS = 1.0  # DeepRacer gives a step 1/15 s; a second is generous and still short
# How often the watchdog looks, as a share of the limit: a call is stopped at most a
# quarter of the limit late.
LOOKS_PER_LIMIT = 4
# A call still running this many limits after it began has swallowed every interruption.
STUCK_AFTER_LIMITS = 4


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
        self.fired = 0.0  # the call the watchdog has interrupted (its `started`)
        self._main = threading.main_thread().ident
        # When a call has swallowed its interruptions for this long, the process cannot
        # go on: `on_stuck` ends it (each process that runs racer code says how).
        self.on_stuck: Callable[[float], None] | None = None

    def begin(self) -> None:
        self.started = time.monotonic()

    def end(self) -> None:
        self.started = 0.0

    def overran(self, started: float) -> bool:
        """Whether the call that began at `started` was interrupted (the caller checks this
        after a call returns: a racer's `except:` may have swallowed the interruption)."""
        return bool(started) and self.fired == started

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        del signum, frame
        # `started` stays set: a racer's bare `except:` that swallows this is interrupted
        # again at the watchdog's next look, and the call is failed when it returns.
        if self.started and self.started == self.fired:
            raise RewardTimeout(self.seconds)

    def _watch(self) -> None:
        pause = self.seconds / LOOKS_PER_LIMIT
        while True:
            time.sleep(pause)
            began = self.started
            if not began:
                continue
            running = time.monotonic() - began
            if running <= self.seconds:
                continue
            self.fired = began
            if running > self.seconds * STUCK_AFTER_LIMITS and self.on_stuck is not None:
                self.on_stuck(self.seconds)
            elif self._main is not None:
                signal.pthread_kill(self._main, signal.SIGALRM)


_ACTIVE: CallLimit | None = None
WATCHDOG_NAME = "reward-call-limit"


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
    threading.Thread(target=limit._watch, name=WATCHDOG_NAME, daemon=True).start()
    _ACTIVE = limit
    return limit


def active() -> CallLimit | None:
    """The limit installed in this process, if any."""
    return _ACTIVE

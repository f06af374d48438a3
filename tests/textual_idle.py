"""A quicker "idle" for Pilot: Textual's own test of idleness in shorter windows, backed
by the app's message queues and its screen's drawing.

After every key `Pilot.press` waits twice for the process to be idle, and `Pilot.pause()`
once more: Textual sleeps 20 ms at a time until a window passes with under 1 ms of CPU.
That is at least 40 ms a key, and on a screen with a ticking clock often more; it was
about half the time of the app's tests. Here the window is 4 ms (with the same 1 ms of
CPU), and a window counts as idle only when every message queue of the app and of the
screen on top is empty, that screen has drawn what changed, and no worker thread is at
work: a window that short can fall wholly in a moment the process (or a starved thread)
was not scheduled, and then only these tell whether work was still waiting.
"""

from __future__ import annotations

import asyncio
from time import monotonic, process_time

import textual.app
import textual.pilot
from textual._context import active_app
from textual.worker import WorkerState

from racer_tui.app.screens.training import RUN_GROUP as TRAINING_RUN_GROUP

WINDOW_S = 0.004
# Textual's own figure, 1 ms of CPU, now in a window of 4 ms: an event loop with a clock
# ticking on screen uses 0.2-0.3 ms of each such window doing nothing, and a thread at work
# (a heat being simulated) uses all of it.
IDLE_CPU_S = 0.001
BUSY = (WorkerState.PENDING, WorkerState.RUNNING)
# Workers that run as long as their screen is open (following a training, or the
# timekeeper's timer feed) are never waited for.
FOLLOWING = frozenset({TRAINING_RUN_GROUP, "timer"})


def _app_quiet() -> bool:
    """Nothing queued for the app or its screen, no worker at work, and the screen drawn
    as it now is (tests read what is painted: the screen repaints on its own timer, 60
    times a second)."""
    try:
        app = active_app.get()
        screen = app.screen
    except Exception:  # no app running here: the CPU alone decides, as in Textual
        return True
    if not app._message_queue.empty():
        return False
    if any(worker.state in BUSY and worker.group not in FOLLOWING for worker in app.workers):
        return False  # a thread at work may be starved of CPU, so it looks idle
    if (
        screen._layout_required
        or screen._scroll_required
        or screen._repaint_required
        or screen._recompose_required
        or screen._dirty_widgets
    ):
        return False
    return all(node._message_queue.empty() for node in screen.walk_children(with_self=True))


async def wait_for_idle(min_sleep: float = WINDOW_S, max_sleep: float = 1.0) -> None:
    """Textual's `wait_for_idle`, with the same arguments and the same limit."""
    start = monotonic()
    while True:
        cpu = process_time()
        await asyncio.sleep(WINDOW_S)
        quiet = process_time() - cpu < IDLE_CPU_S
        elapsed = monotonic() - start
        if elapsed >= max_sleep or (elapsed > min_sleep and quiet and _app_quiet()):
            return


def install() -> None:
    """Used by Pilot's key presses and pauses (both modules import the name)."""
    textual.app.wait_for_idle = wait_for_idle  # type: ignore[attr-defined]
    textual.pilot.wait_for_idle = wait_for_idle  # type: ignore[attr-defined]

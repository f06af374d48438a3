"""Garbage collection for the app a racer or host keeps open for hours.

Python's full (generation 2) collection walks every object the process holds. In the app
those are mostly Textual's: the sections' widgets and, above all, the lines each widget
last rendered (every `Strip` carries seven small caches: about 100,000 objects once every
section has been seen). At Python's default settings a full collection came every dozen
key presses and took 140-260 ms on an idle machine and up to 600 ms beside a training, so
one key in twelve waited that long (`python -m benchmarks.app.soak` measures it).

So, in the long-running app only:
- What lives as long as the app (modules, Textual, each section once it has been shown) is
  frozen out of collection (`gc.freeze`) after a section's first visit.
- Full collections run when input pauses (`IdleCollector`): a timer runs one once nobody
  has pressed a key for a moment, no key is waiting to be handled, and young collections
  have promoted enough objects to be worth it. Python's own automatic ones are made a
  hundred times rarer. Someone who presses keys for minutes without a pause still gets
  one every `BUSY_COLLECT_SECONDS`, between two keys: frequent, so each has little to
  free and is short. (Freezing more does not make them shorter: the sections render
  their lines again as their data changes, so the rendered-line caches are renewed every
  few hundred keys whatever is frozen.)
- What survives an idle collection is not frozen. Frozen objects are still freed when their
  last reference goes, but garbage in a reference cycle stays until everything is unfrozen,
  and Textual's widgets are all cycles: a table's rendered rows, a dialog or a toast
  alive at that moment and removed a little later kept growing the frozen heap (about
  7,000 objects and 0.5 MB per 1,000 actions of the soak benchmark) until the next sweep,
  which under continuous input came once in 20 minutes. Freezing them did not make idle
  collections shorter either: their time goes to freeing the garbage of the last few
  hundred keys, not to walking what lives.
- Every few minutes, at a longer pause with only the sections open, a sweep unfreezes
  everything, collects it all (what was frozen at start-up and has been removed since) and
  freezes what survives again. It waits for calm: no worker running and no screen come or
  gone for a few seconds, so the transient objects of a heat, a sync or a dialog just
  closed are not frozen with what lives.
- Less for each full collection to walk and free (`racer_tui.app.rendered_lines`, in every
  app): a rendered line makes its caches only when it uses them, never caches itself (a
  reference cycle), and a removed widget lets its rendered lines go at once. In the soak
  benchmark, without a training beside it, busy collections freed 8,000-16,000 objects
  instead of 15,000-21,000, and their slowest answer came down from 65 to 45 ms.
- Young collections (generations 0 and 1) run as Python runs them: they are short.
- Worker threads (a heat's simulation) hand the interpreter back every millisecond, not
  every five (`favour_the_interface`), so a key does not wait behind them.
- Textual's memo of background styles is keyed on the colours alone
  (`memoise_background_styles_by_colour`, in every app): Textual's own keeps the rendered
  lines of up to 1,024 widgets long removed, 8-20 MB, and under steady key presses it
  filled within a few hundred keys.
- While input pauses, at most every `TRIM_SECONDS`, the C allocator is asked to give the
  memory it holds free back to the system (`malloc_trim`, glibc only; 0.4-3 ms in an app
  of 250 MB). The app's thread workers (a heat's simulation, a sync) free what they built
  into the allocator, not the system: the process's resident memory crept up by 10-15 MB
  between trims in the soak benchmark with the live objects flat. For the same reason the
  long-running app lets glibc keep at most `MALLOC_ARENAS` arenas (`limit_malloc_arenas`):
  by default every thread may get its own, each holding its own free memory.
"""

from __future__ import annotations

import ctypes
import gc
import sys
import time
from collections.abc import Callable
from functools import lru_cache

from textual._styles_cache import StylesCache
from textual.color import Color
from textual.style import Style

# Seconds after a section's first visit before what it built is frozen out of garbage
# collection (its data loads in workers first).
FREEZE_AFTER_SECONDS = 1.0
# Input paused this long: a full collection now delays nobody's key.
IDLE_SECONDS = 0.4
# How often the idle check runs.
CHECK_SECONDS = 0.1
# A sweep freezes what survives it only this long after the last screen came or went, with
# no worker running: a heat's, a sync's or a dialog's objects being let go are not frozen.
CALM_SECONDS = 5.0
# Generation-1 collections since the last full one before an idle full collection is
# worth running (Python's own threshold is 10, subject to its 25% rule).
IDLE_COLLECT_AFTER = 10
# Generation 2's automatic threshold while the app runs: a hundred times Python's.
AUTOMATIC_FULL_AFTER = 1000
# With keys pressed without a pause, the automatic full collection hardly ever comes:
# Python also waits until what was promoted since the last one is a quarter of the
# long-lived heap (75,000 objects here), and in a soak of 3,000 keys without a pause none
# came while the process grew from 203 MB to 435 MB of garbage. So a full collection is
# also run this long after the last one, at a moment no key is waiting, pause or not.
# Short because frequent: its time goes to freeing what was promoted since the last one,
# not to walking what lives unfrozen (20,000-25,000 objects, 2-3 ms). 20 s apart, one took
# up to 446 ms beside a training; 5 s apart, once the footer stopped building a widget per
# key, 12-20 ms on an idle machine, and a key that met one beside a training waited 94 ms;
# 2 s apart, the soak's longest collection beside a training took 74 ms, its slowest key 60,
# but in a later soak one took 102 ms and the key that met it 114. 1 s apart they took up
# to 171 ms: the sections a dialog covered a second after their first visit had never
# been frozen (98,000 objects walked by every collection). With those frozen once the
# dialog closes (racer_tui.app.application), 43,000 objects stay unfrozen, the longest
# collection beside a training took 95 ms and the slowest key 129 ms (a replay opening,
# itself 52 ms, met one). On an idle machine such a collection takes 9-14 ms: beside a
# training, walking the heap waits on memory the training's process keeps busy.
BUSY_COLLECT_SECONDS = 1.0
# A sweep is due this long after the last one; it waits for input to pause this long
# (a sweep walks everything: about a second beside a training)...
SWEEP_SECONDS = 300.0
SWEEP_IDLE_SECONDS = 3.0
# ...unless it is this overdue: then the next ordinary pause will do.
SWEEP_OVERDUE_SECONDS = 1200.0
# At most this often, while input pauses, free memory goes back to the system.
TRIM_SECONDS = 10.0
# glibc's allocator arenas for the long-running app: the main thread's and one shared by
# the worker threads (glibc's default allows eight per core).
MALLOC_ARENAS = 2
_M_ARENA_MAX = -8  # glibc's mallopt parameter number for the arena limit


def malloc_trim() -> Callable[[], object] | None:
    """glibc's `malloc_trim(0)`, or None where the C library has none (macOS, musl)."""
    try:
        trim = ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None
    trim.argtypes = [ctypes.c_size_t]
    return lambda: trim(0)


def limit_malloc_arenas(arenas: int = MALLOC_ARENAS) -> bool:
    """Let glibc's allocator keep at most `arenas` arenas; False where it cannot (not
    glibc). Arenas already made stay; call it before the app starts its threads."""
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    return bool(mallopt(_M_ARENA_MAX, arenas))


# How long a thread holds the interpreter before another may run (Python's default: 5 ms).
# A heat simulated in a worker thread holds it for whole slices; the key that waits behind
# them waits a slice per hand-over. At 1 ms the timekeeper's keys beside a simulated heat
# answered at p95 35 ms instead of 55 (python -m benchmarks.app.timekeeper).
SWITCH_INTERVAL_SECONDS = 0.001


def favour_the_interface() -> None:
    """Hand the interpreter to the interface thread sooner when a worker thread computes."""
    sys.setswitchinterval(SWITCH_INTERVAL_SECONDS)


# Textual's own, as this module found it (the tests put it back to show the leak).
TEXTUALS_GET_INNER_OUTER = StylesCache.get_inner_outer


def memoise_background_styles_by_colour() -> None:
    """Let removed widgets' rendered lines go.

    Textual (8.2.8) memoises `StylesCache.get_inner_outer` with an `lru_cache(1024)` on the
    method, so each entry's key holds the `StylesCache` it was called on (`self`), and with
    it the rendered lines of its widget long after the widget was removed
    (Textualize/textual#6665, open). Every race view, dialog, toast and table row that
    is built and dropped adds entries until 1,024 widgets' lines are pinned: 8-20 MB, a
    full memo within a few hundred keys of the soak benchmark. The method never reads
    `self` (its answer is two styles made from the two colours), so the memo is kept on
    the colours alone: a handful of entries, and nothing of any widget's.
    Idempotent; a Textual whose method is no longer memoised is left as it is."""
    compute = getattr(TEXTUALS_GET_INNER_OUTER, "__wrapped__", None)
    if compute is None or StylesCache.get_inner_outer is not TEXTUALS_GET_INNER_OUTER:
        return  # not a memoised method, or already replaced

    @lru_cache(maxsize=1024)
    def by_colour(base_background: Color, background: Color) -> tuple[Style, Style]:
        styles: tuple[Style, Style] = compute(None, base_background, background)
        return styles

    def get_inner_outer(
        self: StylesCache, base_background: Color, background: Color
    ) -> tuple[Style, Style]:
        return by_colour(base_background, background)

    StylesCache.get_inner_outer = get_inner_outer  # type: ignore[method-assign, assignment]


class IdleCollector:
    """Moves full collections to the moments when input pauses."""

    def __init__(
        self,
        clock: Callable[[], float] = time.monotonic,
        trim: Callable[[], object] | None = None,
    ) -> None:
        """`trim` returns free memory to the system."""
        self._clock = clock
        self._trim = trim
        self._last_input = clock()
        self._last_sweep = clock()
        self._last_trim = clock()
        self._last_collection = clock()
        self._threshold: tuple[int, int, int] | None = None
        self.collections = 0
        self.busy_collections = 0  # of `collections`, those run while keys kept coming
        self.sweeps = 0
        self.trims = 0
        # The kind of full collection this collector is running ("busy", "idle", "sweep"),
        # None between them: a gc callback tells its own from Python's automatic ones.
        self.running: str | None = None

    def start(self) -> None:
        """Make automatic full collections rare (undone by `stop`)."""
        if self._threshold is None:
            self._threshold = gc.get_threshold()
            young, middle, _ = self._threshold
            gc.set_threshold(young, middle, AUTOMATIC_FULL_AFTER)
            self._last_sweep = self._clock()

    def stop(self) -> None:
        if self._threshold is not None:
            gc.set_threshold(*self._threshold)
            self._threshold = None

    def input_seen(self) -> None:
        self._last_input = self._clock()

    def tick(self, *, quiet: bool, keys_waiting: bool = False) -> bool:
        """Run a full collection if input has paused and one is due, and return free
        memory to the system if that is due; True if a collection ran.
        `quiet`: only the sections are open, so a sweep may freeze what survives it.
        `keys_waiting`: input has arrived that the app has not handled yet."""
        if self._threshold is None or keys_waiting:
            return False
        now = self._clock()
        paused = now - self._last_input
        if paused < IDLE_SECONDS:
            return self._collect_if_long_busy(now)
        collected = self._collect_if_due(now, paused, quiet=quiet)
        if self._trim is not None and now - self._last_trim >= TRIM_SECONDS:
            self._trim()
            self._last_trim = now
            self.trims += 1
        return collected

    def _collect_if_long_busy(self, now: float) -> bool:
        """A full collection while keys keep coming, once `BUSY_COLLECT_SECONDS` have gone
        by without one (never a sweep: what lives is not refrozen mid-typing)."""
        if now - self._last_collection < BUSY_COLLECT_SECONDS:
            return False
        if gc.get_count()[2] < IDLE_COLLECT_AFTER:
            return False
        self._collect("busy")
        self._last_collection = now
        self.collections += 1
        self.busy_collections += 1
        return True

    def _collect(self, kind: str) -> None:
        self.running = kind
        try:
            gc.collect()
        finally:
            self.running = None

    def _collect_if_due(self, now: float, paused: float, *, quiet: bool) -> bool:
        since_sweep = now - self._last_sweep
        sweep = quiet and (
            (since_sweep >= SWEEP_SECONDS and paused >= SWEEP_IDLE_SECONDS)
            or since_sweep >= SWEEP_OVERDUE_SECONDS
        )
        if not sweep and gc.get_count()[2] < IDLE_COLLECT_AFTER:
            return False
        if sweep:
            gc.unfreeze()
            self._last_sweep = now
            self.sweeps += 1
        self._collect("sweep" if sweep else "idle")
        if sweep:
            gc.freeze()
        self._last_collection = now
        self.collections += 1
        return True


def freeze_long_lived() -> None:
    """Collect, then keep everything alive now out of later collections."""
    gc.collect()
    gc.freeze()

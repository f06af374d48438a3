"""Textual's rendered lines, kept only as long as they are of use.

Full collections are what a key can meet in the long-running app
(`racer_tui.app.long_running`); their time goes to walking what lives unfrozen and to
freeing garbage held in reference cycles. Textual's rendered lines are most of both.

**Seven empty caches a line.**

Every `textual.strip.Strip` (one rendered line of one widget) makes seven small caches when
it is built: crop, style, filter, divide, line length, crop-and-extend and offsets. Each is
a `FIFOCache`, an object the garbage collector tracks. In the long-running app, with every
section shown once, about 1,200 lines live unfrozen between sweeps: 8,000 of their 8,400
caches stay empty (the soak benchmark, at its busy collections: 370 lines had used the
divide cache, 226 the filter cache, 18 the line-length cache, one the crop cache). Those
empty caches were a fifth of what each full collection walked, and full collections are
what a key can meet (`racer_tui.app.long_running`).

`make_strip_caches_lazy` keeps each cache out of the line until the line first stores
something in it. Textual's own code is unchanged: reading an absent cache gives a stand-in
that finds nothing, and the first store through it makes the real cache. (Textual's
`Content` already makes its divide cache this way.)

**A line that caches itself.** A line already as long as asked (`adjust_cell_length`), or
divided at its own end (`divide`, the compositor's usual cut), answers itself, and Textual
stores that answer in the line's own cache: the line then refers to itself, and it and its
segments outlive their last use until a full collection finds the cycle. That was most of
the lines a busy collection freed. A cache made here keeps no answer that is the line
itself (answering it again costs a comparison).

**The lines of removed widgets.** A widget removed from the screen (a dialog closed, a race
view left) is garbage in a reference cycle (parent and children refer to each other), so
everything it holds waits for the next full collection. Textual empties a removed widget's
render cache but keeps the lines its styles cache drew (and a table's row, cell and line
caches): 12,000-15,000 of the 20,000 objects a busy collection freed in the soak
benchmark. `let_removed_widgets_lines_go` empties those caches as the widget is unmounted:
the lines are freed at once, by reference counting, as the key that closed the widget is
answered (a few milliseconds), and the collection has only the widgets themselves to free.
"""

from __future__ import annotations

import contextlib
from collections.abc import Hashable
from typing import Any

from textual.cache import FIFOCache
from textual.strip import Strip
from textual.widget import Widget
from textual.widgets import DataTable

# The slots of `Strip` that hold one `FIFOCache` each (Textual 8.x).
STRIP_CACHE_SLOTS = (
    "_divide_cache",
    "_crop_cache",
    "_style_cache",
    "_filter_cache",
    "_line_length_cache",
    "_crop_extend_cache",
    "_offsets_cache",
)


class _AbsentCache:
    """What a line reads for a cache it has not made yet: it finds nothing, and the first
    value stored through it makes the line's real cache."""

    __slots__ = ("_lazy", "_strip")

    def __init__(self, lazy: LazyCache, strip: Strip) -> None:
        self._lazy = lazy
        self._strip = strip

    def get(self, key: Hashable, default: Any = None) -> Any:
        return default

    def __len__(self) -> int:
        return 0

    def __contains__(self, key: object) -> bool:
        return False

    def clear(self) -> None:
        return None

    def __setitem__(self, key: Hashable, value: Any) -> None:
        if not _answers_itself(id(self._strip), value):
            self._lazy.make(self._strip)[key] = value

    set = __setitem__


def _answers_itself(line_id: int, value: Any) -> bool:
    """Whether a cached answer is the line whose id is `line_id`, or a list of lines
    holding it (by id: a cache that kept a reference to its line would be the cycle)."""
    if id(value) == line_id:
        return True
    return isinstance(value, list) and any(id(line) == line_id for line in value)


class LineCache(FIFOCache[Any, Any]):
    """Textual's cache of one line's answers, but never the line itself (no cycle)."""

    __slots__ = ("_owner",)

    def __init__(self, maxsize: int, owner: Strip) -> None:
        super().__init__(maxsize)
        self._owner = id(owner)  # its id: a reference would be the cycle again

    def set(self, key: Any, value: Any) -> None:
        if not _answers_itself(self._owner, value):
            super().set(key, value)

    __setitem__ = set


class LazyCache:
    """A data descriptor over one of `Strip`'s slots: an empty cache is kept as none."""

    def __init__(self, slot: Any, maxsize: int) -> None:
        self.slot = slot  # the slot's own member descriptor
        self.maxsize = maxsize

    def __get__(self, strip: Strip | None, owner: type | None = None) -> Any:
        if strip is None:
            return self
        try:
            return self.slot.__get__(strip, owner)
        except AttributeError:
            return _AbsentCache(self, strip)

    def __set__(self, strip: Strip, cache: Any) -> None:
        # An empty cache is Textual's constructor (the one place it sets these): keep none
        # until one is needed. Nothing is deleted for it: the slot is not set yet there,
        # and deleting an unset slot raises, seven times a line, which was a noticeable
        # part of drawing a screen. Were an empty cache ever set over a made one, the made
        # one stays: its answers stay true, a line never changes.
        if not (isinstance(cache, FIFOCache) and not cache):
            self.slot.__set__(strip, cache)

    def __delete__(self, strip: Strip) -> None:
        with contextlib.suppress(AttributeError):  # never made
            self.slot.__delete__(strip)

    def make(self, strip: Strip) -> FIFOCache[Any, Any]:
        cache = LineCache(self.maxsize, strip)
        self.slot.__set__(strip, cache)
        return cache


def make_strip_caches_lazy() -> bool:
    """Make `Strip`'s caches lazy; True if they are (now or already). Idempotent; a Textual
    whose `Strip` no longer has these slots is left as it is (False)."""
    slots = [Strip.__dict__.get(name) for name in STRIP_CACHE_SLOTS]
    if all(isinstance(slot, LazyCache) for slot in slots):
        return True
    if not all(type(slot).__name__ == "member_descriptor" for slot in slots):
        return False
    # Each cache's size as Textual makes it, read from a line built before the change.
    sample = Strip([])
    sizes: list[int] = []
    for name in STRIP_CACHE_SLOTS:
        size = getattr(getattr(sample, name), "_maxsize", None)
        if not isinstance(size, int):
            return False
        sizes.append(size)
    for name, slot, size in zip(STRIP_CACHE_SLOTS, slots, sizes, strict=True):
        setattr(Strip, name, LazyCache(slot, size))
    return True


# Textual's own, as this module found it.
TEXTUALS_ON_UNMOUNT = Widget._on_unmount


def _on_unmount_letting_lines_go(self: Widget) -> None:
    TEXTUALS_ON_UNMOUNT(self)
    # Textual's private caches, looked up rather than assumed: a Textual without them
    # keeps its lines a little longer, and never fails to remove a widget for it.
    if isinstance(self, DataTable):
        clear = getattr(self, "_clear_caches", None)  # styles, row, cell and line caches
    else:
        clear = getattr(getattr(self, "_styles_cache", None), "clear", None)
    if callable(clear):
        clear()


def let_removed_widgets_lines_go() -> None:
    """Empty a widget's caches of rendered lines when it is unmounted. Idempotent."""
    Widget._on_unmount = _on_unmount_letting_lines_go  # type: ignore[method-assign]

"""A rendered line makes each of its caches only when it first stores something in it."""

from __future__ import annotations

import gc
import weakref

from rich.segment import Segment
from rich.style import Style
from textual.app import App
from textual.cache import FIFOCache
from textual.strip import Strip
from textual.widgets import DataTable, Static

from racer_tui.app.rendered_lines import (
    STRIP_CACHE_SLOTS,
    LazyCache,
    LineCache,
    let_removed_widgets_lines_go,
    make_strip_caches_lazy,
)


def made_caches(strip: Strip) -> set[str]:
    """The caches this line holds (read through the slots themselves, not the stand-ins)."""
    made = set()
    for name in STRIP_CACHE_SLOTS:
        lazy = Strip.__dict__[name]
        assert isinstance(lazy, LazyCache)
        try:
            lazy.slot.__get__(strip, Strip)
        except AttributeError:
            continue
        made.add(name)
    return made


def line() -> Strip:
    return Strip([Segment("hello ", Style(bold=True)), Segment("world")])


def test_a_new_line_holds_no_cache_and_tracks_fewer_objects() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    assert made_caches(strip) == set()
    # Nothing the collector walks hangs off a new line but its segments' list.
    assert not [o for o in gc.get_referents(strip) if isinstance(o, FIFOCache)]
    assert strip.text == "hello world"


def test_a_cache_is_made_by_its_first_store_and_then_answers() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    first = strip.crop(0, 5)
    assert made_caches(strip) == {"_crop_cache"}
    assert first.text == "hello"
    assert strip.crop(0, 5) is first  # answered from the cache made by the first crop
    styled = strip.apply_style(Style(italic=True))
    assert made_caches(strip) == {"_crop_cache", "_style_cache"}
    assert strip.apply_style(Style(italic=True)) is styled
    parts = strip.divide([3, 11])
    assert [part.text for part in parts] == ["hel", "lo world"]
    assert strip.divide([3, 11]) is parts


def test_an_absent_cache_reads_as_an_empty_one() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    cache = strip._crop_cache
    assert len(cache) == 0 and not cache and cache.get((0, 1)) is None
    assert (0, 1) not in cache
    cache.clear()
    assert made_caches(strip) == set()


def test_a_cache_textual_sets_with_content_is_kept() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    filled: FIFOCache[tuple[int, int], Strip] = FIFOCache(16)
    filled[(0, 1)] = strip
    strip._crop_cache = filled
    assert strip._crop_cache is filled
    fresh = line()
    fresh._crop_cache = FIFOCache(16)  # an empty one (Textual's constructor) is kept as none
    assert made_caches(fresh) == set()
    # An empty one set over a made one changes nothing: the made one's answers stay true.
    strip._crop_cache = FIFOCache(16)
    assert strip._crop_cache is filled and strip.crop(0, 1) is strip


def test_it_is_idempotent_and_keeps_textuals_sizes() -> None:
    assert make_strip_caches_lazy()
    before = {name: Strip.__dict__[name] for name in STRIP_CACHE_SLOTS}
    assert make_strip_caches_lazy()  # every app in a process calls it
    assert {name: Strip.__dict__[name] for name in STRIP_CACHE_SLOTS} == before
    sizes = {name: lazy.maxsize for name, lazy in before.items()}
    assert sizes["_crop_cache"] == 16 and sizes["_style_cache"] == 16
    assert sizes["_divide_cache"] == 4
    strip = Strip([Segment("x" * 40)])
    for index in range(20):
        strip.crop(index, index + 1)
    assert len(strip._crop_cache) == 16  # a made cache is still Textual's bounded FIFO


def test_a_line_never_caches_itself() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    # Divided at its own end and asked for its own length, a line answers itself; kept in
    # its own cache, that answer would make the line a reference cycle.
    assert strip.divide([strip.cell_length]) == [strip]
    assert strip.adjust_cell_length(strip.cell_length) is strip
    assert made_caches(strip) == set()
    parts = strip.divide([3, strip.cell_length])  # other answers are kept
    assert strip.divide([3, strip.cell_length]) is parts
    assert strip.adjust_cell_length(strip.cell_length) is strip  # kept out of the made cache
    cache = strip._divide_cache
    assert isinstance(cache, LineCache) and len(cache) == 1


def test_a_line_no_longer_used_is_freed_without_a_collection() -> None:
    assert make_strip_caches_lazy()
    strip = line()
    strip.divide([strip.cell_length])
    strip.adjust_cell_length(strip.cell_length)
    strip.crop(0, 3)
    collected = gc.isenabled()
    gc.disable()
    try:
        seen = weakref_to_list(strip)
        del strip
        assert seen() is None  # freed by its last reference going: no cycle held it
    finally:
        if collected:
            gc.enable()


class _Segments(list[Segment]):
    """A list of segments a weak reference can watch (plain lists cannot be)."""


def weakref_to_list(strip: Strip) -> weakref.ref[_Segments]:
    """A weak reference to the line's list of segments, which goes when the line does."""
    segments = _Segments(strip._segments)
    strip._segments = segments
    return weakref.ref(segments)


async def test_a_removed_widget_lets_its_lines_go() -> None:
    let_removed_widgets_lines_go()
    app: App[None] = App()
    async with app.run_test(size=(40, 10)) as pilot:
        label = Static("hello\nworld")
        table: DataTable[str] = DataTable()
        await app.screen.mount(label, table)
        table.add_columns("a", "b")
        table.add_row("1", "2")
        await pilot.pause()
        assert label._styles_cache._cache and table._line_cache.keys()
        await label.remove()
        await table.remove()
        assert not label._styles_cache._cache
        assert not table._line_cache.keys() and not table._styles_cache._cache

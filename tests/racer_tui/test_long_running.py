"""The long-running app's garbage collection: full collections wait for a pause in the
input and freeze nothing; a sweep frees garbage that was frozen and, when only the
sections are open, freezes what survives it."""

from __future__ import annotations

import gc
import itertools
import weakref
from collections.abc import Iterator

import pytest
from textual._styles_cache import StylesCache
from textual.app import App, ComposeResult
from textual.color import Color
from textual.containers import Vertical
from textual.widgets import Label

from racer_tui.app.long_running import (
    AUTOMATIC_FULL_AFTER,
    BUSY_COLLECT_SECONDS,
    CALM_SECONDS,
    IDLE_COLLECT_AFTER,
    IDLE_SECONDS,
    SWEEP_IDLE_SECONDS,
    SWEEP_OVERDUE_SECONDS,
    SWEEP_SECONDS,
    TEXTUALS_GET_INNER_OUTER,
    TRIM_SECONDS,
    IdleCollector,
    freeze_long_lived,
    limit_malloc_arenas,
    malloc_trim,
    memoise_background_styles_by_colour,
)


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class Cycle:
    """An object in a reference cycle: only the collector frees it."""

    def __init__(self) -> None:
        self.me = self


@pytest.fixture(autouse=True)
def nothing_frozen() -> None:
    """The process as the app finds it at start: the suite's own freezing (tests/conftest.py)
    undone, so what these tests see frozen is the app's doing."""
    gc.unfreeze()


@pytest.fixture
def collector() -> Iterator[tuple[IdleCollector, Clock]]:
    clock = Clock()
    collector = IdleCollector(clock)
    threshold = gc.get_threshold()
    collector.start()
    try:
        yield collector, clock
    finally:
        collector.stop()
        gc.unfreeze()  # the test process collects as usual again
        assert gc.get_threshold() == threshold


def promote() -> None:
    """As many generation-1 collections as make an idle full collection due."""
    for _ in range(IDLE_COLLECT_AFTER):
        gc.collect(1)


def test_automatic_full_collections_are_made_rare_and_restored(
    collector: tuple[IdleCollector, Clock],
) -> None:
    assert gc.get_threshold()[2] == AUTOMATIC_FULL_AFTER
    collector[0].stop()
    assert gc.get_threshold()[2] != AUTOMATIC_FULL_AFTER


def test_no_full_collection_while_keys_come_or_none_is_due(
    collector: tuple[IdleCollector, Clock],
) -> None:
    idle, clock = collector
    promote()
    idle.input_seen()
    clock.now += IDLE_SECONDS / 2
    assert not idle.tick(quiet=True)  # a key was pressed a moment ago
    clock.now += IDLE_SECONDS
    assert not idle.tick(quiet=True, keys_waiting=True)  # a key is waiting to be handled
    gc.collect()  # nothing promoted since: none due
    assert not idle.tick(quiet=True)
    assert idle.collections == 0


def test_keys_without_a_pause_still_get_a_full_collection_now_and_then(
    collector: tuple[IdleCollector, Clock],
) -> None:
    # Someone pressing keys without ever pausing for IDLE_SECONDS: the garbage of their
    # keys is still collected, every BUSY_COLLECT_SECONDS, when no key is waiting.
    idle, clock = collector
    cycle = Cycle()
    garbage = weakref.ref(cycle)
    promote()
    del cycle
    for _ in range(int(BUSY_COLLECT_SECONDS / 0.1) - 2):  # a key every tenth of a second
        idle.input_seen()
        clock.now += 0.1
        assert not idle.tick(quiet=True)
    assert garbage() is not None
    clock.now += 0.5
    idle.input_seen()
    assert not idle.tick(quiet=True, keys_waiting=True)  # never ahead of a waiting key
    assert idle.tick(quiet=True)
    assert garbage() is None
    assert idle.busy_collections == 1 and gc.get_freeze_count() == 0  # not a sweep
    idle.input_seen()
    clock.now += 0.1
    promote()
    assert not idle.tick(quiet=True)  # the next one is BUSY_COLLECT_SECONDS away


def test_an_idle_collection_frees_cycles_and_freezes_nothing(
    collector: tuple[IdleCollector, Clock],
) -> None:
    idle, clock = collector
    clock.now += IDLE_SECONDS * 2
    cycle = Cycle()
    garbage = weakref.ref(cycle)
    promote()  # it survives into generation 2
    del cycle
    gc.collect(1)
    assert garbage() is not None  # young collections never look at generation 2
    assert idle.tick(quiet=False)
    assert garbage() is None
    # Alive at a quiet idle collection and dropped just after, as a footer key or a toast
    # is: it must not outlive the next idle collection by being frozen in between.
    removed_soon = Cycle()
    removed = weakref.ref(removed_soon)
    promote()
    assert idle.tick(quiet=True)
    assert gc.get_freeze_count() == 0
    del removed_soon
    promote()
    assert idle.tick(quiet=True)
    assert removed() is None


def test_a_sweep_frees_garbage_that_was_frozen_and_freezes_what_lives(
    collector: tuple[IdleCollector, Clock],
) -> None:
    idle, clock = collector
    clock.now += IDLE_SECONDS * 2
    removed_later = Cycle()
    frozen_garbage = weakref.ref(removed_later)
    freeze_long_lived()  # as after a section's first visit
    del removed_later  # now garbage, but frozen: ordinary collections never see it
    promote()
    assert idle.tick(quiet=True)
    assert frozen_garbage() is not None
    clock.now += SWEEP_SECONDS  # due, but the pause is short: only an ordinary collection
    idle.input_seen()
    clock.now += IDLE_SECONDS
    promote()
    assert idle.tick(quiet=True)
    assert idle.sweeps == 0 and frozen_garbage() is not None
    clock.now += SWEEP_IDLE_SECONDS  # a longer pause, but a dialog is open: no sweep
    assert not idle.tick(quiet=False)
    assert idle.sweeps == 0
    long_lived = Cycle()
    assert idle.tick(quiet=True)  # the dialog closed: the sweep
    assert idle.sweeps == 1
    assert frozen_garbage() is None
    # What lives on is out of later collections again: frozen, in no generation.
    assert gc.is_tracked(long_lived)
    assert not any(o is long_lived for generation in range(3) for o in gc.get_objects(generation))
    assert gc.get_freeze_count() > 0


def test_an_overdue_sweep_takes_the_next_short_pause(
    collector: tuple[IdleCollector, Clock],
) -> None:
    idle, clock = collector
    clock.now += SWEEP_OVERDUE_SECONDS
    idle.input_seen()
    clock.now += IDLE_SECONDS
    assert idle.tick(quiet=True)
    assert idle.sweeps == 1


def test_free_memory_goes_back_to_the_system_while_input_pauses_not_on_every_tick() -> None:
    clock = Clock()
    trims: list[float] = []
    idle = IdleCollector(clock, trim=lambda: trims.append(clock.now))
    idle.start()
    try:
        for _ in range(16):  # a pause every 5 s for 80 s; nothing for the collector to do
            clock.now += 5.0
            idle.tick(quiet=False)
        assert len(trims) == idle.trims == 8  # every other pause, not every one
        assert all(b - a >= TRIM_SECONDS for a, b in itertools.pairwise(trims))
        clock.now += 60.0
        idle.input_seen()  # a key just now: no trim until input pauses again
        idle.tick(quiet=False)
        assert idle.trims == 8
        clock.now += IDLE_SECONDS * 2
        idle.tick(quiet=False, keys_waiting=True)
        assert idle.trims == 8
        idle.tick(quiet=False)
        assert idle.trims == 9
    finally:
        idle.stop()


def test_the_c_library_arena_limit_is_accepted_where_there_is_one() -> None:
    if malloc_trim() is None:
        pytest.skip("this C library is not glibc")
    assert limit_malloc_arenas()


def test_the_c_library_trim_runs_where_there_is_one() -> None:
    trim = malloc_trim()
    if trim is None:
        pytest.skip("this C library has no malloc_trim (not glibc)")
    trim()  # returns memory; must not raise


class Rebuilds(App[None]):
    """The minimal reproduction of Textualize/textual#6665: a list rebuilt over and over."""

    def compose(self) -> ComposeResult:
        yield Vertical(id="cards")

    async def rebuild(self) -> None:
        cards = self.query_one("#cards", Vertical)
        await cards.remove_children()
        await cards.mount_all(Label(f"card {n}", classes="card") for n in range(40))


def _styles_caches_alive() -> int:
    gc.collect()
    return sum(1 for thing in gc.get_objects() if type(thing) is StylesCache)


async def _styles_caches_kept_by_rebuilds(app: Rebuilds) -> tuple[int, int]:
    """(styles caches alive beyond those of widgets on screen, widgets on screen) after
    rebuilding the list ten times."""
    before = _styles_caches_alive()  # other tests' (in this worker process): counted apart
    async with app.run_test(size=(80, 24)) as pilot:
        for _ in range(10):
            await app.rebuild()
            await pilot.pause()
        on_screen = len(app.screen.query("*")) + 1  # the widgets and the screen
        kept = _styles_caches_alive() - before - on_screen
        assert "card 39" in str(app.screen.query(Label).last().render())  # still draws
    return kept, on_screen


async def test_textuals_memo_keeps_removed_widgets_rendered_lines() -> None:
    # The upstream behaviour this works around: with Textual's own memo on the method, ten
    # rebuilds of 40 cards leave hundreds of removed widgets' styles caches alive. When
    # this fails, Textual has fixed it and memoise_background_styles_by_colour can go.
    memoise_background_styles_by_colour()
    patched = StylesCache.get_inner_outer
    StylesCache.get_inner_outer = TEXTUALS_GET_INNER_OUTER  # type: ignore[method-assign]
    try:
        TEXTUALS_GET_INNER_OUTER.cache_clear()
        kept, _ = await _styles_caches_kept_by_rebuilds(Rebuilds())
        assert kept > 100  # of the 400 cards removed
    finally:
        StylesCache.get_inner_outer = patched  # type: ignore[method-assign]
        TEXTUALS_GET_INNER_OUTER.cache_clear()


async def test_removed_widgets_rendered_lines_are_let_go() -> None:
    memoise_background_styles_by_colour()
    memoise_background_styles_by_colour()  # twice, as every app in a process calls it
    kept, on_screen = await _styles_caches_kept_by_rebuilds(Rebuilds())
    # What remains belongs to widgets still on screen (and a few Textual is done with).
    assert kept <= on_screen // 10
    # The memo itself still answers, with the styles Textual's gave.
    colour, other = Color(10, 20, 30), Color(200, 100, 0, 0.5)
    ours = StylesCache().get_inner_outer(colour, other)
    assert ours == TEXTUALS_GET_INNER_OUTER.__wrapped__(None, colour, other)


def test_only_the_long_running_app_hands_the_interpreter_to_its_interface_sooner() -> None:
    import sys

    from racer_tui.app.application import create_app
    from racer_tui.app.long_running import SWITCH_INTERVAL_SECONDS

    before = sys.getswitchinterval()
    try:
        create_app()
        assert sys.getswitchinterval() == before
        create_app(long_running=True)  # what `racer-tui` starts: heats run in threads
        assert sys.getswitchinterval() == SWITCH_INTERVAL_SECONDS < before
    finally:
        sys.setswitchinterval(before)


async def test_a_sweep_waits_for_calm_before_it_freezes_what_survives() -> None:
    """A sweep freezes what survives it: not while a dialog is open, a worker computes or a
    screen has just come or gone (their objects are on their way out), but a training
    followed for hours does not keep the app from ever being calm."""
    import threading

    from racer_tui.app.application import create_app
    from racer_tui.app.screens.help import HelpScreen
    from racer_tui.app.screens.training import RUN_GROUP
    from tests.racer_tui.screens.tui_helpers import settle

    now = [0.0]

    def calm_after(seconds: float) -> bool:
        now[0] += seconds
        return app._calm()

    app = create_app(start="garage")
    app.calm_clock = lambda: now[0]
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        app._calm()  # the screens seen so far
        assert calm_after(CALM_SECONDS)
        await pilot.press("question_mark")
        await settle(pilot)
        assert isinstance(app.screen, HelpScreen)
        assert not calm_after(CALM_SECONDS)  # a screen over the sections
        await pilot.press("escape")
        await settle(pilot)
        assert not calm_after(0.1)  # just closed: its objects are still being let go
        assert calm_after(CALM_SECONDS)
        release = threading.Event()
        app.run_worker(release.wait, thread=True, group="heat")
        await pilot.pause()
        assert not calm_after(CALM_SECONDS)  # a heat computes in a thread
        follow = threading.Event()
        app.run_worker(follow.wait, thread=True, group=RUN_GROUP)
        release.set()
        await pilot.pause(0.1)
        assert calm_after(CALM_SECONDS)  # following a training is no transient work
        follow.set()


async def test_a_section_seen_first_under_a_dialog_is_frozen_once_the_dialog_closes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The first visit's freeze waits for the dialog to close instead of being left to a
    sweep: steady keys never give a sweep its calm, and every full collection walked the
    section's objects instead (130-170 ms each in a soak beside a training)."""
    from racer_tui.app import application
    from racer_tui.app.application import create_app
    from racer_tui.app.screens.help import HelpScreen
    from tests.racer_tui.screens.tui_helpers import settle

    monkeypatch.setattr(application, "FREEZE_AFTER_SECONDS", 3600.0)
    app = create_app(start="garage", long_running=True)
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("question_mark")  # before the first visit's freeze is due
            await settle(pilot)
            assert isinstance(app.screen, HelpScreen)
            monkeypatch.setattr(application, "FREEZE_AFTER_SECONDS", 0.05)
            app._freeze_if_quiet()  # the first visit's freeze comes due now
            await pilot.pause(0.3)
            assert gc.get_freeze_count() == 0  # not with the dialog's objects
            await pilot.press("escape")
            await settle(pilot)
            await pilot.pause(0.3)
            assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()

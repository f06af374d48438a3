"""The footer keeps no key it no longer shows, and the app keeps nothing per section switch.

These count objects; they never time anything. The leak they guard against was Textual's
footer holding every key it ever showed (see `racer_tui.widgets.footer`).
"""

from __future__ import annotations

import functools
import gc
from typing import Any, ClassVar

from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.pilot import Pilot
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import Footer, Label
from textual.widgets._footer import FooterKey

from racer_tui.app import create_app
from racer_tui.screens.dialogs import ConfirmDialog
from racer_tui.screens.help import HelpScreen
from racer_tui.widgets.footer import RacerFooter
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import settle


def _alive(kind: type[Any]) -> int:
    gc.collect()
    return sum(1 for thing in gc.get_objects() if issubclass(type(thing), kind))


def _objects() -> int:
    """Live objects after a full collection, Textual's and Rich's memo caches emptied
    first: they are bounded (up to 16,384 entries) and refill as they are used, so they
    only blur a count taken to find what grows without bound."""
    for thing in gc.get_objects():
        if type(thing) is functools._lru_cache_wrapper and str(
            getattr(thing, "__module__", "")
        ).startswith(("textual", "rich")):
            thing.cache_clear()
    gc.collect()
    return len(gc.get_objects())


def _modes(footer: type[Footer]) -> type[App[None]]:
    """The minimal reproduction: five modes, each a screen with a footer and a binding."""

    class Section(Screen[None]):
        BINDINGS: ClassVar[list[BindingType]] = [Binding("x", "noop", "Something")]

        def compose(self) -> ComposeResult:
            yield Label("a section")
            yield footer()

    class Modes(App[None]):
        MODES: ClassVar[dict[str, Any]] = {str(n): Section for n in range(1, 6)}
        BINDINGS: ClassVar[list[BindingType]] = [
            Binding(str(n), f"switch_mode('{n}')", f"Section {n}") for n in range(1, 6)
        ]

        def on_mount(self) -> None:
            self.switch_mode("1")

    return Modes


async def _switch(pilot: Pilot[Any], times: int) -> None:
    for press in range(times):
        await pilot.press("12345"[press % 5])  # waits for the app to go idle


async def _keys_kept(footer: type[Footer]) -> int:
    """Footer keys alive after 25 section switches, beyond those alive after 5."""
    app = _modes(footer)()
    async with app.run_test(size=(80, 24)) as pilot:
        await _switch(pilot, 5)
        before = _alive(FooterKey)
        await _switch(pilot, 25)
        return _alive(FooterKey) - before


async def test_textuals_own_footer_keeps_every_key_it_showed() -> None:
    # Upstream behaviour (Textual 8.2.8), kept so the workaround can go when it changes:
    # this test fails then, and RacerFooter.forget_removed_keys is no longer needed.
    assert await _keys_kept(Footer) > 25


async def test_racer_footer_forgets_the_keys_it_no_longer_shows() -> None:
    assert await _keys_kept(RacerFooter) <= 0


async def test_switching_sections_and_opening_dialogs_keeps_no_objects() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await _switch(pilot, 10)  # warm-up: every section shown twice
        await _dialogs(pilot, 5)
        widgets, objects = _alive(Widget), _objects()
        # 125 actions: ample, since without the fix 60 already keep 26,600 objects; more
        # only cost CI time (this was the suite's slowest test at 250).
        await _switch(pilot, 100)
        await _dialogs(pilot, 25)
        assert _alive(Widget) <= widgets
        # Textual's per-widget caches (bounded) still grow by about 1,000 objects whatever
        # the number of actions (900 after 60, 1,250 after 250). Without the footer's fix,
        # 60 of these actions already kept 26,600 objects and 206 widgets.
        assert _objects() - objects < 2_500


async def _dialogs(pilot: Pilot[Any], times: int) -> None:
    """Open and close a dialog `times` times: the Garage's delete question (answered no)
    and every fifth time the help screen."""
    await pilot.press("1")
    await settle(pilot)
    for time in range(times):
        key = "question_mark" if time % 5 == 0 else "d"
        await pilot.press(key)
        assert isinstance(pilot.app.screen, HelpScreen if key == "question_mark" else ConfirmDialog)
        await pilot.press("escape")

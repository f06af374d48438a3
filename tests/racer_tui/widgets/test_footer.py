"""The footer: what it shows and what its keys do, and that it builds nothing per change
of keys; and the app keeps nothing per section switch.

The object counts never time anything. They guard against Textual's footer, which builds
a widget per key at every change of keys and holds every key it ever showed (see
`racer_tui.app.widgets.footer`).
"""

from __future__ import annotations

import functools
import gc
from typing import Any, ClassVar

from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.dom import DOMNode
from textual.pilot import Pilot
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import Footer, Label
from textual.widgets._footer import FooterKey

from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.help import HelpScreen
from racer_tui.app.widgets.footer import RacerFooter, ShownKey, fitting
from sim.garage.options import new_model
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.tui_helpers import painted, settle


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


def _modes(footer: type[Widget]) -> type[App[None]]:
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


# Section switches counted after a warm-up: Textual's footer keeps a key and builds about
# 100 nodes per switch, so ten show it plainly (each of its switches costs a fifth of a
# second of CSS work, which is why there are not more).
SWITCHES = 10


async def _keys_kept(footer: type[Widget]) -> int:
    """Footer keys alive after SWITCHES section switches, beyond those alive after 5."""
    app = _modes(footer)()
    async with app.run_test(size=(80, 24)) as pilot:
        await _switch(pilot, 5)
        before = _alive(FooterKey)
        await _switch(pilot, SWITCHES)
        return _alive(FooterKey) - before


async def test_textuals_own_footer_keeps_every_key_it_showed() -> None:
    # Upstream behaviour (Textual 8.2.8), kept to show why racer-tui draws its own footer:
    # when this fails, Textual's footer could be looked at again.
    assert await _keys_kept(Footer) > SWITCHES


async def _nodes_left_to_collect(footer: type[Widget]) -> int:
    """Nodes (widgets and Textual's style nodes) that SWITCHES section switches leave to
    the cycle collector, after a warm-up."""
    app = _modes(footer)()
    async with app.run_test(size=(80, 24)) as pilot:
        await _switch(pilot, 5)
        gc.collect()
        gc.disable()  # so that all of it is still there to count
        try:
            await _switch(pilot, SWITCHES)
            gc.set_debug(gc.DEBUG_SAVEALL)
            gc.collect()
        finally:
            gc.set_debug(0)
            gc.enable()
        left = sum(isinstance(thing, DOMNode) for thing in gc.garbage)
        gc.garbage.clear()
        return left


class NoFooter(Label):
    """A screen's last line without any footer: what switching sections leaves anyway."""


async def test_the_footer_builds_nothing_when_the_keys_change() -> None:
    # Textual's footer builds a widget per key (and two style nodes for each) at every
    # change of keys: about 100 nodes per switch here, each some forty objects in cycles
    # that only a full collection frees. RacerFooter repaints one line instead.
    without_a_footer = await _nodes_left_to_collect(NoFooter)
    assert await _nodes_left_to_collect(Footer) > without_a_footer + SWITCHES * 20
    assert await _nodes_left_to_collect(RacerFooter) == without_a_footer


async def test_switching_sections_and_opening_dialogs_keeps_no_objects() -> None:
    new_model("ada")
    app = create_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await _switch(pilot, 10)  # warm-up: every section shown twice
        await _dialogs(pilot, 5)
        widgets, objects = _alive(Widget), _objects()
        # 60 actions: without the fix they keep 26,600 objects and 206 widgets; more only
        # cost CI time (this was the suite's slowest test at 250).
        await _switch(pilot, 45)
        await _dialogs(pilot, 15)
        assert _alive(Widget) <= widgets
        # Textual's per-widget caches (bounded) still grow by about 1,000 objects whatever
        # the number of actions (900 after 60, 1,250 after 250).
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


class Keys(Screen[None]):
    """Keys with long labels, one of them disabled while `locked`."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("a", "count('alpha')", "Alpha the first key"),
        Binding("b", "count('bravo')", "Bravo the second key", tooltip="Counts a bravo"),
        Binding("l", "count('locked')", "Locked key"),
        Binding("c", "count('charlie')", "Charlie the third key"),
        Binding("d", "count('delta')", "Delta the last key"),
        Binding("question_mark", "help", "Help"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.pressed: list[str] = []

    def compose(self) -> ComposeResult:
        yield Label("keys")
        yield RacerFooter()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        return None if parameters == ("locked",) else True  # None: shown, disabled

    def action_count(self, name: str) -> None:
        self.pressed.append(name)

    def action_help(self) -> None:
        self.pressed.append("help")


class KeysApp(App[None]):
    def __init__(self) -> None:
        super().__init__()
        self.bells = 0

    def on_mount(self) -> None:
        self.push_screen(Keys())

    def bell(self) -> None:
        self.bells += 1


def _placed(app: App[Any], description: str) -> int:
    """The column where the key labelled `description` starts."""
    footer = app.screen.query_one(RacerFooter)
    return next(place.start for place in footer.placed() if place.key.description == description)


async def test_a_click_on_a_key_presses_it_and_a_disabled_key_only_rings() -> None:
    app = KeysApp()
    async with app.run_test(size=(130, 24)) as pilot:
        await pilot.pause()
        screen = app.screen
        assert isinstance(screen, Keys)
        await pilot.click(RacerFooter, offset=(_placed(app, "Bravo the second key") + 1, 0))
        await pilot.click(RacerFooter, offset=(_placed(app, "Locked key") + 1, 0))
        assert screen.pressed == ["bravo"]
        assert app.bells == 1
        footer = screen.query_one(RacerFooter)
        await pilot.hover(RacerFooter, offset=(_placed(app, "Bravo the second key") + 1, 0))
        assert footer.tooltip == "Counts a bravo"
        await pilot.hover(RacerFooter, offset=(_placed(app, "Alpha the first key") + 1, 0))
        assert footer.tooltip is None  # that key has none


async def test_at_80_columns_the_later_keys_give_way_and_help_stays() -> None:
    app = KeysApp()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        footer = app.screen.query_one(RacerFooter)
        line = painted(footer)
        assert line.startswith("a Alpha the first key b Bravo the second key l Locked key")
        assert "? Help" in line  # declared last, shown always
        assert "Delta" not in line and "^p" not in line  # no room: on the help screen
        assert all(place.end <= 80 for place in footer.placed())
    async with KeysApp().run_test(size=(130, 24)) as pilot:
        await pilot.pause()
        line = painted(pilot.app.screen.query_one(RacerFooter))
        assert "Delta the last key" in line
        assert line.rstrip().endswith("^p palette")


def _key(key: str, description: str, short: str = "") -> ShownKey:
    action = "app.help" if key == "?" else f"do_{key}"
    return ShownKey(key, key, description, action, True, "", short)


def test_short_labels_keep_every_key_before_any_is_left_out() -> None:
    """Issue 42's walk: at 60 columns the Nights footer left out c and p, the keys a host
    needs by the end of a night. Short labels come first; only then do keys give way."""
    keys = (
        _key("o", "Open night", "Open"),
        _key("c", "Close night", "Close"),
        _key("p", "Projector"),
        _key("?", "Help"),
    )
    wide = fitting(keys, 60, compact=True)
    assert [key.description for key in wide] == ["Open night", "Close night", "Projector", "Help"]
    # "o Open night c Close night p Projector ? Help " is 46 cells; the short one is 34.
    narrow = fitting(keys, 40, compact=True)
    assert [key.description for key in narrow] == ["Open", "Close", "Projector", "Help"]
    tight = fitting(keys, 28, compact=True)
    assert [key.description for key in tight] == ["Open", "Close", "Help"]


async def test_the_nights_footer_keeps_close_and_projector_at_60_columns() -> None:
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        await the_nights_screen(pilot)
        line = painted(app.screen.query_one(RacerFooter))
        assert "c Close" in line and "p Projector" in line and "? Help" in line
    async with create_app(start="league").run_test(size=(120, 40)) as pilot:
        await the_nights_screen(pilot)
        line = painted(pilot.app.screen.query_one(RacerFooter))
        assert "c Close night" in line  # the long labels wherever they fit

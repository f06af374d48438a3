"""SVG snapshots of each screen at 80x24 and 120x40, built with the CLI's app factory.

Deterministic by construction: a fixed data folder per test (paths show in the garage), no
trained weights (their hash would change every run), the welcome demo frozen at one moment
of the reference driver's (deterministic) race, and no blinking cursors.
Update them after a deliberate change with `pytest tests/racer_tui/snapshots --snapshot-update`
and look at the SVGs before committing.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input, Select, TextArea

from racer_tui.app.application import create_app
from racer_tui.app.widgets.demo_race import DemoRace
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

Compare = Callable[..., bool]


def two_models() -> None:
    new_model("hairpin-hero")
    new_model("lidar-lou", sensors=["lidar"], track="speedway", continuous=True)


def prepared(then: Callable[[Pilot[Any]], Awaitable[None]] | None = None) -> Any:
    """A run_before: let workers finish, stop cursors blinking, then `then`."""

    async def run_before(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        if then is not None:
            await then(pilot)
            await settle(pilot)
        for widget in pilot.app.screen.query("Input, TextArea"):
            if isinstance(widget, Input | TextArea):
                widget.cursor_blink = False

    return run_before


@SIZES
def test_welcome(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def freeze_demo(pilot: Pilot[Any]) -> None:
        demo = pilot.app.screen.query_one(DemoRace)
        demo.freeze(7.5)

    assert snap_compare(create_app(), terminal_size=size, run_before=prepared(freeze_demo))


@SIZES
def test_garage(snap_compare: Compare, size: tuple[int, int]) -> None:
    two_models()
    assert snap_compare(create_app(), terminal_size=size, run_before=prepared())


@SIZES
def test_editor_car_tab(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def open_editor(pilot: Pilot[Any]) -> None:
        await pilot.press("n", *"first-car")

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(open_editor))


@SIZES
def test_editor_action_space_tab(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def open_actions(pilot: Pilot[Any]) -> None:
        await pilot.press("n", "f3")
        pilot.app.screen.query_one("#steering-levels", Select).value = 7

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(open_actions))


@SIZES
def test_editor_hyperparameters_with_a_problem(
    snap_compare: Compare, size: tuple[int, int]
) -> None:
    async def bad_batch(pilot: Pilot[Any]) -> None:
        await pilot.press("n", *"ok-name", "f4")
        pilot.app.screen.query_one("#hp-batch_size", Input).value = "7"
        await pilot.pause()
        await pilot.press("ctrl+s")

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(bad_batch))


@SIZES
def test_editor_reward_checked(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def check(pilot: Pilot[Any]) -> None:
        await pilot.press("n", "ctrl+r")

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(check))


@SIZES
def test_tracks(snap_compare: Compare, size: tuple[int, int]) -> None:
    assert snap_compare(create_app(start="tracks"), terminal_size=size, run_before=prepared())


@SIZES
def test_races(snap_compare: Compare, size: tuple[int, int]) -> None:
    assert snap_compare(create_app(start="races"), terminal_size=size, run_before=prepared())


@SIZES
def test_help(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def open_help(pilot: Pilot[Any]) -> None:
        await pilot.press("question_mark")

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(open_help))


@SIZES
def test_delete_confirmation(snap_compare: Compare, size: tuple[int, int]) -> None:
    two_models()

    async def ask(pilot: Pilot[Any]) -> None:
        await pilot.press("d")

    assert snap_compare(create_app(), terminal_size=size, run_before=prepared(ask))


@SIZES
def test_import_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def ask(pilot: Pilot[Any]) -> None:
        await pilot.press("i")

    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=prepared(ask))

"""SVG snapshots of the dialogs the screens' own snapshots do not open, at the three sizes:
each opens centred over its screen, with every field, its words and its buttons readable.
The delete question and the model import dialog are in test_snapshots.py."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input

from league.nights import new_night
from league.store import open_league
from racer_tui.app import create_app
from racer_tui.screens.training import LeaveWhileTraining
from sim.track_catalog import resolve_track
from tests.racer_tui.snapshots.sizes import SIZES
from tests.racer_tui.snapshots.test_snapshots import Compare, prepared, two_models


def pressing(*keys: str) -> Any:
    async def press(pilot: Pilot[Any]) -> None:
        for key in keys:
            await pilot.press(key)
            await pilot.pause()

    return prepared(press)


@SIZES
def test_clone_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    two_models()
    assert snap_compare(create_app(), terminal_size=size, run_before=pressing("c"))


@SIZES
def test_train_budget_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    two_models()
    assert snap_compare(create_app(), terminal_size=size, run_before=pressing("t"))


@SIZES
def test_track_import_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    app = create_app(start="tracks")
    assert snap_compare(app, terminal_size=size, run_before=pressing("i"))


@SIZES
def test_open_night_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=pressing("n", "o"))


@SIZES
def test_add_entrant_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    two_models()
    with open_league() as league:
        new_night(league, resolve_track("beginner-oval"), name="friday")
    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=pressing("n", "a"))


@SIZES
def test_new_season_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=pressing("n", "s"))


@SIZES
def test_leave_while_training_question(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def ask(pilot: Pilot[Any]) -> None:
        # What quitting asks while a training runs (a real run is not needed to draw it).
        await pilot.app.push_screen(LeaveWhileTraining("hairpin-hero"))

    two_models()
    app = create_app(start="training")
    assert snap_compare(app, terminal_size=size, run_before=prepared(ask))


@SIZES
def test_someone_elses_reward_code_question(
    snap_compare: Compare, size: tuple[int, int], deepracer_dir: Path, fixed_home: Path
) -> None:
    # A friend's DeepRacer folder brings its reward_function.py: asked before importing.
    folder = fixed_home / "from-a-friend"
    shutil.copytree(deepracer_dir / "drfc-model", folder)
    (folder / "reward_function.py").write_text("def reward_function(params):\n    return 1.0\n")

    async def ask(pilot: Pilot[Any]) -> None:
        await pilot.press("i")
        pilot.app.screen.query_one("#path", Input).value = str(folder)
        await pilot.press("enter")

    two_models()
    assert snap_compare(create_app(), terminal_size=size, run_before=prepared(ask))

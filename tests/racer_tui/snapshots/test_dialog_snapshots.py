"""SVG snapshots of the dialogs the screens' own snapshots do not open, at the three sizes:
each opens centred over its screen, with every field, its words and its buttons readable.
The delete question and the model import dialog are in test_snapshots.py; the other
yes-or-no questions share its dialog, so two more with long words stand for them."""

from __future__ import annotations

import shutil
from datetime import date
from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot
from textual.widgets import Input

from league.nights import new_night
from league.opening import open_league
from racer_tui.app.application import create_app
from racer_tui.app.screens import sync
from racer_tui.app.screens.training import LeaveWhileTraining
from racer_tui.app.widgets import job_line
from sim.tracks.catalog import resolve_track
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES
from tests.racer_tui.snapshots.test_snapshots import Compare, prepared, two_models

FRIDAY = date(2026, 3, 6)  # a fixed day: the screens show it


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
        new_night(league, resolve_track("beginner-oval"), name="friday", held_on=FRIDAY)
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


@SIZES
def test_discard_changes_question(snap_compare: Compare, size: tuple[int, int]) -> None:
    # Esc in the model editor with a name typed: asked before the form is thrown away.
    app = create_app(start="garage")
    assert snap_compare(app, terminal_size=size, run_before=pressing("n", *"draft", "escape"))


@SIZES
def test_set_up_a_store_question(
    snap_compare: Compare,
    size: tuple[int, int],
    fixed_home: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # s on the Sync screen with a shared folder that is not there (yet): set one up? The
    # sync's failure behind the question says when it failed: at a fixed time here.
    monkeypatch.setattr(job_line, "local_clock", lambda wall: "21:05")
    monkeypatch.setattr(sync, "local_time", lambda iso: "21:05")

    async def ask(pilot: Pilot[Any]) -> None:
        await pilot.press("y")
        await settle(pilot)
        field = pilot.app.screen.query_one("#sync-url", Input)
        field.focus()
        field.value = f"dir:{fixed_home / 'league-share'}"
        await pilot.press("enter")
        await settle(pilot)
        await pilot.press("s")

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=prepared(ask))

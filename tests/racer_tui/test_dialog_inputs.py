"""Inputs keep every key (issue 42, point 3): keys typed without a pause right after the key
that opens a dialog, and a paste, arrive whole in the dialog's field. The keys are queued as
a terminal delivers them (`burst`: all at once), not pressed one by one as Pilot does."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

import pytest
from textual.screen import Screen
from textual.widgets import Input

import racer_tui.app.application as app_module
import racer_tui.app.screens.garage as garage_module
from racer_tui.app.application import create_app
from racer_tui.app.keys_as_delivered import burst, drain, paste
from racer_tui.app.screens.dialogs import ImportDialog, InputDialog
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.nights import NewNightDialog, NewSeasonDialog, NightsScreen
from racer_tui.app.screens.tracks import TrackImportDialog
from racer_tui.app.screens.train_dialog import TrainDialog
from sim.garage.folder import ModelError, ModelFolder, list_models
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import trained_model

TYPED = "abcdefghij" * 20  # 200 characters, no pause between them
PASTED = "/a/pasted/path with spaces/" * 4
CLEAR = ["ctrl+a", "ctrl+k"]  # what the racer types first over a suggested value

CASES: dict[str, tuple[str, Callable[[], object], list[str], type[Screen[Any]]]] = {
    "train budget": ("garage", lambda: new_model("one"), ["t"], TrainDialog),
    "clone name": ("garage", lambda: new_model("one"), ["c"], InputDialog),
    "export path": ("garage", lambda: trained_model("one"), ["x"], InputDialog),
    "model import": ("garage", lambda: new_model("one"), ["i"], ImportDialog),
    "track import": ("tracks", lambda: None, ["i"], TrackImportDialog),
}


@pytest.mark.parametrize("case", list(CASES))
async def test_keys_typed_right_after_opening_a_dialog_all_arrive(case: str) -> None:
    start, prepare, opening, dialog = CASES[case]
    prepare()
    app = create_app(start=start)
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, [*opening, *CLEAR, *TYPED])
        await drain(pilot)
        assert isinstance(app.screen, dialog)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == TYPED
        paste(app, PASTED)
        await drain(pilot)
        assert field.value == TYPED + PASTED


async def test_a_paste_right_after_opening_a_dialog_arrives_whole() -> None:
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["t", *CLEAR])
        paste(app, "12")
        await drain(pilot)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == "12"


@pytest.mark.parametrize(
    ("typed", "kept"),
    [(["backspace", "backspace", "5"], "5"), (["7"], "7"), (["1", "2"], "12")],
)
async def test_the_train_budget_typed_in_the_burst_that_opened_it_is_kept(
    typed: list[str], kept: str
) -> None:
    # The walk of issue 42: t, then Backspace Backspace 5 in one burst left the field empty
    # (the suggested budget is selected when the field takes focus: typing replaces it).
    new_model("one")
    app = create_app(start="training")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["t", *typed])
        await drain(pilot)
        assert isinstance(app.screen, TrainDialog)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == kept


async def test_a_key_whose_binding_takes_long_holds_the_keys_after_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Opening the Training section for the first time can take seconds on a busy machine,
    # longer than the app's last-resort clock for a key in flight: the keys after `t` still
    # wait for its binding (the app runs it before it reads its next key) and its dialog.
    monkeypatch.setattr(app_module, "KEY_FLIGHT_SECONDS", 0.05)
    opening = GarageScreen.action_train_model

    async def slow_opening(screen: GarageScreen) -> None:
        await asyncio.sleep(0.5)
        await opening(screen)

    monkeypatch.setattr(GarageScreen, "action_train_model", slow_opening)
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["t", *CLEAR, "1", "2"])
        await drain(pilot)
        assert isinstance(app.screen, TrainDialog)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == "12"


def _slow_listing(monkeypatch: pytest.MonkeyPatch, seconds: float, fails: bool = False) -> None:
    listing = list_models

    def slow() -> list[ModelFolder]:
        time.sleep(seconds)
        if fails:
            raise ModelError("the models folder cannot be read")
        return listing()

    monkeypatch.setattr(garage_module, "list_models", slow)


async def test_a_key_typed_as_the_garage_opens_waits_for_its_models(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _slow_listing(monkeypatch, 0.5)
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        burst(app, ["t", *CLEAR, "7"])  # before the list has been read
        await drain(pilot)
        assert isinstance(app.screen, TrainDialog)
        assert app.screen._name == "one"
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == "7"


async def test_a_list_that_cannot_be_read_holds_keys_only_for_a_moment(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(app_module, "READY_WAIT_SECONDS", 0.2)
    _slow_listing(monkeypatch, 0.05, fails=True)
    new_model("one")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        burst(app, ["t"])
        await drain(pilot)
        assert isinstance(app.screen, GarageScreen)
        said = [notification.message for notification in app._notifications]
        assert any("have not been read" in message and "ctrl+r" in message for message in said)


@pytest.mark.parametrize(("key", "dialog"), [("o", NewNightDialog), ("s", NewSeasonDialog)])
async def test_keys_typed_after_a_nights_dialog_key_arrive_in_its_dialog(
    key: str, dialog: type[Screen[Any]]
) -> None:
    # The Nights screen reads the seasons in a worker before its dialog opens: the keys
    # typed right after `o` or `s` went to the Nights screen (issue 42's last known gap).
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["n"])
        await drain(pilot)
        assert isinstance(app.screen, NightsScreen)
        burst(app, [key, *"friday"])
        await drain(pilot)
        assert isinstance(app.screen, dialog)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == "friday"


async def test_keys_typed_right_after_enter_go_to_the_field_enter_moved_to() -> None:
    # Enter in a field moves the focus when its dialog hears the field was submitted, a
    # message after the key: the keys typed right after Enter went into the field left
    # behind ("cy Enter reference" became racer "cyre", model "ference").
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await drain(pilot)
        burst(app, ["n"])
        await drain(pilot)
        burst(app, ["s", *"spring", "enter", *"10,6,4"])
        await drain(pilot)
        assert isinstance(app.screen, NewSeasonDialog)
        assert app.screen.query_one("#season-name", Input).value == "spring"
        assert app.screen.query_one("#season-points", Input).value == "10,6,4"

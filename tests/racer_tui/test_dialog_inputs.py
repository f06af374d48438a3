"""Inputs keep every key (issue 42, point 3): keys typed without a pause right after the key
that opens a dialog, and a paste, arrive whole in the dialog's field. The keys are queued as
a terminal delivers them (`burst`: all at once), not pressed one by one as Pilot does."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from textual.screen import Screen
from textual.widgets import Input

from racer_tui.app import create_app
from racer_tui.keys_as_delivered import burst, drain, paste
from racer_tui.screens.dialogs import ImportDialog, InputDialog
from racer_tui.screens.tracks import TrackImportDialog
from sim.garage.options import new_model
from tests.racer_tui.screens.tui_helpers import trained_model

TYPED = "abcdefghij" * 20  # 200 characters, no pause between them
PASTED = "/a/pasted/path with spaces/" * 4
CLEAR = ["ctrl+a", "ctrl+k"]  # what the racer types first over a suggested value

CASES: dict[str, tuple[str, Callable[[], object], list[str], type[Screen[Any]]]] = {
    "train budget": ("garage", lambda: new_model("one"), ["t"], InputDialog),
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
        assert isinstance(app.screen, InputDialog)
        field = app.focused
        assert isinstance(field, Input)
        assert field.value == kept

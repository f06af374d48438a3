"""The Train dialog: a time budget and, for a racer preparing for a bracket, the cars to
train among (`racer-tui train --opponent`); what cannot be raced is said under the field."""

from __future__ import annotations

from typing import Any

import pytest
from textual.widgets import Input, Static

from racer_tui.app.application import create_app
from racer_tui.app.screens.train_dialog import TrainDialog, split_opponents
from racer_tui.app.screens.training import TrainingRequest, TrainingScreen
from racer_tui.app.widgets.training_charts import TrainingFigures, counters
from sim.garage.options import new_model
from sim.training import events
from tests.racer_tui.screens.tui_helpers import painted, settle


def test_opponents_are_split_on_commas_each_named_once() -> None:
    assert split_opponents(" rival , reference,, rival ") == ("rival", "reference")
    assert split_opponents("  ") == ()


async def _dialog(pilot: Any, monkeypatch: pytest.MonkeyPatch) -> list[TrainingRequest]:
    app = pilot.app
    screen = app.screen
    assert isinstance(screen, TrainingScreen)
    requested: list[TrainingRequest] = []
    monkeypatch.setattr(screen, "_run", requested.append)
    await pilot.press("t")
    await settle(pilot)
    assert isinstance(app.screen, TrainDialog)
    return requested


async def _type(pilot: Any, field: str, text: str) -> None:
    app = pilot.app
    app.screen.query_one(field, Input).value = text
    await pilot.pause()


async def test_a_model_trains_among_the_cars_named(monkeypatch: pytest.MonkeyPatch) -> None:
    new_model("seer", sensors=("sector_lidar",))
    app = create_app(start="training")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        requested = await _dialog(pilot, monkeypatch)
        await _type(pilot, "#minutes", "3")
        await pilot.press("tab")  # on to the opponents (Enter in the budget trains)
        assert app.focused is app.screen.query_one("#opponents", Input)
        await _type(pilot, "#opponents", "nobody-here")
        await pilot.press("enter")
        problem = painted(app.screen.query_one("#problem", Static))
        assert "nobody-here" in problem  # said under the field; the dialog stays
        assert isinstance(app.screen, TrainDialog) and not requested
        await _type(pilot, "#opponents", "reference")
        await pilot.press("enter")
        await settle(pilot)
        assert not isinstance(app.screen, TrainDialog)
        assert [(r.model, r.minutes, r.opponents) for r in requested] == [
            ("seer", 3.0, ("reference",))
        ]


async def test_a_model_that_cannot_see_other_cars_is_told_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    new_model("blind")  # vector state only: no other car is in it
    app = create_app(start="training")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        requested = await _dialog(pilot, monkeypatch)
        await _type(pilot, "#opponents", "reference")
        await pilot.press("ctrl+s")
        problem = " ".join(painted(app.screen.query_one("#problem", Static)).split())
        assert problem.startswith("A model that races among objects needs a camera or a lidar")
        assert not requested
        # Without opponents it trains as ever.
        await _type(pilot, "#opponents", "")
        await pilot.press("ctrl+s")
        await settle(pilot)
        assert [r.opponents for r in requested] == [()]


def test_the_training_view_says_what_the_car_trains_among() -> None:
    figures = TrainingFigures()
    figures.fold(events.Started(0.0, "seer", "reinvent_base", ("lidar",), 8, "scratch", 0, 5, 1))
    assert "against" not in counters(figures).plain
    among = TrainingFigures()
    among.fold(
        events.Started(
            0.0,
            "seer",
            "reinvent_base",
            ("lidar",),
            8,
            "scratch",
            0,
            5,
            1,
            opponents=("rival", "reference"),
        )
    )
    assert "against rival, reference" in counters(among).plain

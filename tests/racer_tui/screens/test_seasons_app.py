"""Seasons from the app: the host creates one in the nights screen (with one-sentence
problems for a blank or taken name), opens a night in it, and sees it on the night."""

from __future__ import annotations

from typing import Any

from textual.app import App
from textual.screen import Screen
from textual.widgets import Input, Select

from league.nights import list_nights
from league.opening import open_league
from league.seasons import get_season, list_seasons, new_season
from racer_tui.app.application import create_app
from racer_tui.app.screens.nights import NewNightDialog, NewSeasonDialog, season_problem
from sim.foundation.home import data_home
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle


def showing(app: App[Any]) -> Screen[Any]:
    """The screen on top (a plain call, so a type checker does not keep an earlier
    isinstance narrowing of `app.screen`)."""
    return app.screen


def test_season_problems_are_one_sentence_each() -> None:
    assert season_problem("  ", "", []) == "Give the season a name, for example Spring 2025."
    assert season_problem("Spring", "", ["spring"]) == (
        "There is already a season called 'Spring'; pick another name."
    )
    assert "whole numbers" in (season_problem("Autumn", "25,x", []) or "")
    assert "never more for a worse place" in (season_problem("Autumn", "10,20", []) or "")
    assert season_problem("Autumn", "10, 5, 1", ["spring"]) is None


async def test_a_host_creates_a_season_and_opens_a_night_in_it() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        new_season(league, "winter")
    app = create_app(start="league")
    async with app.run_test(size=(100, 30)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)

        await pilot.press("s")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, NewSeasonDialog)
        await pilot.press("enter", "enter")  # nothing typed
        problem = dialog.query_one("#problem")
        assert "Give the season a name" in painted(problem)
        await pilot.press(*"Winter", "enter", "enter")  # taken, whatever the case
        assert app.screen is dialog
        assert "already a season called 'Winter'" in painted(problem)
        name = dialog.query_one("#season-name", Input)
        name.value = "Spring 2025"
        dialog.query_one("#season-points", Input).value = "10,6,3,1"
        name.focus()
        await pilot.press("ctrl+s")  # from the name field, as in every form: create
        await settle(pilot)
        assert showing(app) is nights
        assert "Created season Spring 2025" in notes.text()

        await pilot.press("o")  # the new season is chosen for the new night
        await settle(pilot)
        night_dialog = app.screen
        assert isinstance(night_dialog, NewNightDialog)
        season = night_dialog.query_one("#night-season", Select)
        labels = {value: label for label, value in season._options}
        assert labels[season.value] == "Spring 2025"
        await pilot.press(*"opener", "ctrl+s")
        await settle(pilot)
        assert showing(app) is nights
        assert "season Spring 2025" in painted(nights.query_one("#night-rules"))

    restarted = create_app(start="league")  # the next night, after a restart of the app
    async with restarted.run_test(size=(100, 30)) as pilot:
        await the_nights_screen(pilot)
        await pilot.press("o")
        await settle(pilot)
        season = restarted.screen.query_one("#night-season", Select)
        labels = {value: label for label, value in season._options}
        assert labels[season.value] == "Spring 2025"  # still the current season

    with open_league() as league:
        spring = get_season(league, "Spring 2025")
        assert spring.points == (10, 6, 3, 1)
        assert [s.name for s in list_seasons(league)] == ["winter", "Spring 2025"]
        (night,) = list_nights(league)
        assert night.name == "opener" and night.season_id == spring.id

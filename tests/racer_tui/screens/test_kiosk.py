"""Issue 42, point 7: the projector is a kiosk. Esc does nothing there, no key opens
another screen (sections, help, the command palette), and leaving takes q or ctrl+q and a
confirmation: started from the command line it quits the program, opened from the League
screen it goes back there."""

from __future__ import annotations

import pytest
from textual.widgets import Button
from textual.widgets._toast import Toast, ToastRack  # not exported: the test's subject

from league.nights import add_entrant, new_night
from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from racer_tui.app.screens.kiosk import LeaveKiosk
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.projector import ProjectorScreen
from sim.foundation.home import data_home
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import settle

# Every key that opens something elsewhere in the app, and the ones a passer-by presses.
STRAY_KEYS = (
    "escape", "1", "2", "3", "4", "5", "6", "question_mark", "f1", "ctrl+p", "tab",
    "enter", "space", "p", "x", "escape", "ctrl+c",
)  # fmt: skip


def a_night() -> str:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), rules=RaceRules(), name="friday")
        add_entrant(league, night, "ana", "reference")
    return night.id


async def test_the_night_projector_started_alone_opens_nothing_and_quits_when_asked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    night_id = a_night()
    app = create_app(projector_night=night_id)
    quits: list[object] = []
    monkeypatch.setattr(app, "exit", lambda *args, **kwargs: quits.append(args))
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        projector = app.screen
        assert isinstance(projector, NightProjectorScreen)
        stack, mode = list(app.screen_stack), app.current_mode
        for key in STRAY_KEYS:
            await pilot.press(key)
            assert app.screen is projector, f"{key} left the projector"
        assert list(app.screen_stack) == stack and app.current_mode == mode
        await pilot.press("q")
        assert isinstance(app.screen, LeaveKiosk)
        await pilot.press("ctrl+p", "1", "question_mark", "n")  # the question is a kiosk too
        assert app.screen is projector and not quits
        await pilot.press("ctrl+q")
        assert isinstance(app.screen, LeaveKiosk)
        # Staying on the left and leaving on the right, as every confirmation in the app.
        ids = [button.id for button in app.screen.query(Button)]
        assert ids == ["stay", "leave"]
        await pilot.press("y")
        await pilot.pause()
        assert quits  # the program ends: nothing of the app is left behind it


async def test_the_league_projector_goes_back_to_the_league_after_asking() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ada", [11.0]))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("p")
        await settle(pilot)
        projector = app.screen
        assert isinstance(projector, ProjectorScreen)
        for key in STRAY_KEYS:
            await pilot.press(key)
            assert app.screen is projector, f"{key} left the projector"
        await pilot.press("q", "n")
        assert app.screen is projector
        await pilot.press("q", "y")
        assert isinstance(app.screen, LeagueScreen)


async def test_the_hosts_notes_stay_off_the_venues_screen() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ada", [11.0]))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24), notifications=True) as pilot:
        await settle(pilot)
        await pilot.press("p")
        await settle(pilot)
        assert isinstance(app.screen, ProjectorScreen)
        app.notify("Training of blue-fox finished: the time limit was reached.")
        await settle(pilot)
        toasts = list(app.screen.query_one(ToastRack).query(Toast))
        assert toasts and all(not toast.visible for toast in toasts)  # noted, not shown

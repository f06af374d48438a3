"""Every screen and dialog at 80x24, with the long names real leagues have: nothing is cut.

A table column past the right edge (a table that scrolls sideways), a footer key that does
not fit, or a widget that reaches past the terminal's edge is something the racer cannot
read; this walk visits each screen and dialog with such data and names what is cut.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import replace
from typing import Any

import pytest
from textual.app import App
from textual.pilot import Pilot
from textual.screen import ModalScreen
from textual.widget import Widget
from textual.widgets import DataTable, Input, TextArea

from league.nights import add_entrant, draw_heats, new_night, run_heats
from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from racer_tui.app.widgets.footer import RacerFooter
from sim.foundation.home import data_home
from sim.garage.options import new_model
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.drivers import resolve_driver
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import painted, settle, trained_model

SIZE = (80, 24)
# As long as names get in a real league (a model name may have 64 characters, a racer's 100).
LONG_MODEL = "reinvent-2018-centerline-speed-v3-continuous"
LONG_RACER = "Alexandra Montgomery-Fitzgerald"
SHORT = RaceRules(window_seconds=20.0)


def a_busy_league() -> None:
    """Models, recorded races and a league night part-way, with long names."""
    trained_model(LONG_MODEL)
    new_model("lidar-lou", sensors=["lidar"], track="speedway", continuous=True)
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        for number, racer in enumerate([LONG_RACER, "bob", "Chidimma Okonkwo-Adeyemi"]):
            record_race(
                league,
                race_result(
                    racer,
                    [12.0 + number, 11.5 + number],
                    offtracks=[1, 3],
                    model=LONG_MODEL if number == 0 else "bolt",
                    started_at=f"2024-05-0{number + 1}T19:00:00.000Z",
                ),
            )
        night = new_night(league, oval, rules=SHORT, name="Friday night at the makerspace")
        add_entrant(league, night, LONG_RACER, "reference")
        add_entrant(league, night, "bob", "reference")
        draw_heats(league, night, seed=7)
        run_heats(league, night, oval, resolve_driver, limit=1)
        trial = run_race(oval, SHORT, racer=LONG_RACER)
        record_race(league, replace(trial, started_at="2024-05-04T19:00:00.000Z"), night.id)


def cut_off(app: App[Any]) -> list[str]:
    """What on the current screen cannot be read whole at the terminal's size."""
    screen = app.screen
    width = app.size.width
    problems: list[str] = []
    for footer in screen.query(RacerFooter):
        painted_line = painted(footer)
        for place in footer.placed():
            shown = f"{place.key.display} {place.key.description}".strip()
            if footer.region.x + place.end > width or shown not in painted_line:
                problems.append(f"footer key {place.key.description!r} is cut")
    for table in screen.query(DataTable):
        if not table.region.width:
            continue  # on a hidden tab
        needs, has = table.virtual_size.width, table.scrollable_content_region.width
        if needs > has:
            problems.append(f"table #{table.id} needs {needs} columns and has {has}")
    if isinstance(screen, ModalScreen):
        for dialog in screen.query(".dialog"):
            region = dialog.region
            left, right = region.x, width - region.right
            top, bottom = region.y, app.size.height - region.bottom
            if abs(left - right) > 1 or abs(top - bottom) > 1:
                problems.append(f"the dialog is not centred ({region})")
            taller = dialog.virtual_size.height > dialog.scrollable_content_region.height
            if taller and not dialog.show_vertical_scrollbar:
                problems.append("the dialog's last lines are cut off, with no scroll bar")
    for widget in screen.query(Widget):
        # Below the bottom edge is fine: the container scrolls (and says so with its bar).
        if widget.region.width and widget.region.right > width:
            problems.append(f"{widget!r} reaches past the right edge ({widget.region})")
        elif widget.show_horizontal_scrollbar and not isinstance(widget, Input | TextArea):
            # (Text fields and the code editor scroll long lines sideways, as editors do.)
            problems.append(f"{widget!r} scrolls sideways")
    return problems


Steps = Callable[[Pilot[Any]], Awaitable[None]]


def keys(*pressed: str) -> Steps:
    async def press(pilot: Pilot[Any]) -> None:
        for key in pressed:
            await pilot.press(key)
            await settle(pilot)

    return press


async def a_timed_heat(pilot: Pilot[Any]) -> None:
    """A physical car's heat with laps captured, one of them over the resets limit."""
    from racer_tui.app.screens.timekeeper import TimekeeperScreen, TimekeeperSetup

    setup = TimekeeperSetup(resolve_track("reinvent_base"), SHORT, LONG_RACER, LONG_MODEL)
    keeper = TimekeeperScreen(setup)
    await pilot.app.push_screen(keeper)
    keeper.clock = lambda: 100.0
    await pilot.press("space")
    keeper.clock = lambda: 109.8
    await pilot.press("r", "r", "r", "r", "l")
    await settle(pilot)


# place -> (the section it starts from, the keys that lead there, the screen it shows).
# The garage's second row is the trained model (rows sort by name).
PLACES: dict[str, tuple[str, Steps, str]] = {
    "garage": ("garage", keys(), "GarageScreen"),
    "delete dialog": ("garage", keys("d"), "ConfirmDialog"),
    "import dialog": ("garage", keys("i"), "ImportDialog"),
    "track import dialog": ("tracks", keys("i"), "TrackImportDialog"),
    "export dialog": ("garage", keys("down", "x"), "InputDialog"),
    "clone dialog": ("garage", keys("c"), "InputDialog"),
    "editor car tab": ("garage", keys("e"), "ModelEditorScreen"),
    "editor action space tab": ("garage", keys("e", "f3"), "ModelEditorScreen"),
    "editor hyperparameters tab": ("garage", keys("e", "f4"), "ModelEditorScreen"),
    "editor reward tab": ("garage", keys("e", "f5"), "ModelEditorScreen"),
    "evaluation": ("garage", keys("down", "v"), "EvaluationScreen"),
    "tracks": ("tracks", keys(), "TracksScreen"),
    "races": ("races", keys(), "RacesScreen"),
    "race view": ("races", keys("s"), "RaceScreen"),
    "training": ("training", keys(), "TrainingScreen"),
    "league": ("league", keys(), "LeagueScreen"),
    "league export dialog": ("league", keys("x"), "InputDialog"),
    "nights": ("league", keys("n"), "NightsScreen"),
    "open night dialog": ("league", keys("n", "o"), "NewNightDialog"),
    "add entrant dialog": ("league", keys("n", "a"), "AddEntrantDialog"),
    "new season dialog": ("league", keys("n", "s"), "NewSeasonDialog"),
    "projector": ("league", keys("p"), "ProjectorScreen"),
    "sync": ("league", keys("y"), "SyncScreen"),
    "help": ("garage", keys("question_mark"), "HelpScreen"),
    "timekeeper": ("league", a_timed_heat, "TimekeeperScreen"),
}


@pytest.mark.parametrize("place", list(PLACES))
async def test_nothing_is_cut_at_80x24(place: str) -> None:
    a_busy_league()
    section, steps, screen = PLACES[place]
    app = create_app(start=section)
    async with app.run_test(size=SIZE) as pilot:
        await settle(pilot)
        await steps(pilot)
        assert type(app.screen).__name__ == screen
        assert cut_off(app) == []

"""A bracket night in the app: once the heats are raced, k draws the bracket on the Nights
screen, r races its next match live and leaving the race view records it; the Nights
screen and the projector draw the bracket as it advances."""

from __future__ import annotations

from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input, Static

from league.bracket_records import read_bracket
from league.live_match import live_match_path, read_live_match
from league.opening import open_league
from league.store import default_db_path
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.head_to_head_screen import HeadToHeadScreen
from racer_tui.app.screens.night_bracket import DrawBracketDialog
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.nights import NightsScreen
from sim.foundation.home import data_home
from tests.league.test_bracket_nights import qualified_night
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for


def bracket_text(screen: NightsScreen) -> str:
    return painted(screen.query_one("#bracket", Static))


async def race_the_next_match(pilot: Pilot[Any], nights: NightsScreen, night_id: str) -> None:
    await pilot.press("r")
    await wait_for(pilot, lambda: isinstance(pilot.app.screen, HeadToHeadScreen))
    view = pilot.app.screen
    assert isinstance(view, HeadToHeadScreen)
    # Raced live, it tells the night's projector where it is (another racer-tui, often).
    path = live_match_path(default_db_path(), night_id)
    await wait_for(pilot, lambda: read_live_match(path, night_id) is not None)
    on_air = read_live_match(path, night_id)
    assert on_air is not None and on_air.title == "Final" and on_air.match_id == "W1-1"
    assert [car.racer for car in on_air.cars] == ["dee", "cy"]  # the grid: higher seed first
    await pilot.press("e")  # to the end, asked: the room is watching
    assert isinstance(pilot.app.screen, ConfirmDialog)
    await pilot.press("y")
    await wait_for(pilot, lambda: view.at_end and view.result is not None)
    await wait_for(pilot, lambda: getattr(read_live_match(path, night_id), "state", "") == "over")
    await pilot.press("escape")
    await wait_for(pilot, lambda: pilot.app.screen is nights)
    assert not path.exists()  # left: the projector goes back to the night
    await settle(pilot)


async def test_a_host_draws_the_bracket_and_races_it_to_its_champion() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = qualified_night(league)  # dee, cy, bob, ana qualified; eve set no lap
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        title = nights.query_one("#bracket-title")
        assert "Bracket: none yet, k draws it" in painted(title)
        await pilot.press("r")  # every heat is raced: r says what comes next
        await settle(pilot)
        assert "heats are all raced" in notes.text("error")
        assert "draw a bracket from its standings (k)" in notes.text("error")
        await pilot.press("k")
        dialog = app.screen
        assert isinstance(dialog, DrawBracketDialog)
        await pilot.press("1", "enter")  # a bracket of one
        await pilot.press("tab", "enter")  # laps left at 3
        assert app.screen is dialog
        # Four qualified (eve set no lap): a bracket of more is said in the dialog.
        assert "Qualifiers is a number from 2 to 4" in painted(dialog.query_one("#problem"))
        dialog.query_one("#bracket-size", Input).value = "5"
        await pilot.press("ctrl+s")
        assert app.screen is dialog
        dialog.query_one("#bracket-laps", Input).value = "0"
        dialog.query_one("#bracket-size", Input).value = "2"
        await pilot.press("ctrl+s")
        assert "Laps is a whole number from 1 to 99" in painted(dialog.query_one("#problem"))
        dialog.query_one("#bracket-laps", Input).value = "1"
        await pilot.press("ctrl+s")
        await wait_for(pilot, lambda: "Final" in bracket_text(nights))
        assert "Drew the bracket of 2 racers" in notes.text()
        assert "next W1-1 (r)" in painted(title)
        shown = bracket_text(nights)
        assert "dee" in shown and "cy" in shown and "ana" not in shown

        await race_the_next_match(pilot, nights, night.id)
        await wait_for(pilot, lambda: "Champion" in bracket_text(nights))
        assert "Recorded W1-1: dee beat cy." in notes.text()
        await pilot.press("r")  # nothing is left to race: said, not raced
        await settle(pilot)
        assert "bracket is decided; close the night (c)" in notes.text("error")

        await pilot.press("p")
        projector = app.screen
        assert isinstance(projector, NightProjectorScreen)
        await wait_for(pilot, lambda: projector.state is not None)
        await settle(pilot)
        board = painted(projector.query_one("#np-standings"))
        assert "Final" in board and "✓ dee" in board
        assert "Champion: dee" in painted(projector.query_one("#np-heat"))
    with open_league() as league:
        drawn = read_bracket(league, night.id)
        assert drawn is not None and drawn.final_order() is not None


async def test_leaving_a_match_before_its_finish_is_asked_and_records_nothing() -> None:
    """The host walk: Esc a few seconds into the final recorded the simulation's result,
    which was over long before the room had seen the race, and crowned a champion."""
    from dataclasses import replace

    from league.bracket_nights import draw_night_bracket
    from racer_tui.app.screens.dialogs import ConfirmDialog
    from sim.race.rules import HEAD_TO_HEAD_RULES

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = qualified_night(league)
        draw_night_bracket(league, night, size=2, rules=replace(HEAD_TO_HEAD_RULES, lap_count=1))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("r")
        await wait_for(pilot, lambda: isinstance(app.screen, HeadToHeadScreen))
        view = app.screen
        assert isinstance(view, HeadToHeadScreen)
        assert "Final (W1-1): head-to-head, 1 lap" in painted(view.query_one("#h2h-title"))
        await wait_for(pilot, lambda: view.result is not None)  # simulated, not yet shown
        await pilot.press("escape")
        await wait_for(pilot, lambda: isinstance(app.screen, ConfirmDialog))
        await pilot.press("n")  # keep watching
        await wait_for(pilot, lambda: app.screen is view)
        await pilot.press("escape")
        await wait_for(pilot, lambda: isinstance(app.screen, ConfirmDialog))
        await pilot.press("y")  # leave unrecorded
        await wait_for(pilot, lambda: app.screen is nights)
        await settle(pilot)
        assert "left before its race finished" in notes.text("warning")
        assert "Recorded" not in notes.text()
    with open_league() as league:
        drawn = read_bracket(league, night.id)
        assert drawn is not None and not drawn.races  # nothing recorded: r races it again


async def test_what_the_night_would_refuse_is_said_before_a_dialog_opens() -> None:
    """The host walk: k, a and c opened their dialog or question, then refused what was
    filled in."""
    from dataclasses import replace

    from league.bracket_nights import draw_night_bracket
    from league.nights import add_entrant
    from racer_tui.app.screens.dialogs import ConfirmDialog
    from racer_tui.app.screens.nights import AddEntrantDialog
    from sim.race.rules import HEAD_TO_HEAD_RULES

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = qualified_night(league)
        add_entrant(league, night, "fay", "reference")  # entered, not yet drawn
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("k")
        await settle(pilot)
        assert app.screen is nights
        assert "is still qualifying (1 entrant has not raced their heat)" in notes.text("warning")
    with open_league() as league:
        from league.nights import entrants, withdraw_entrant

        fay = next(e for e in entrants(league, night) if e.racer == "fay")
        withdraw_entrant(league, night, fay.id, "host")
        draw_night_bracket(league, night, size=2, rules=replace(HEAD_TO_HEAD_RULES, lap_count=1))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        for key in ("a", "c", "k"):
            await pilot.press(key)
            await settle(pilot)
            assert app.screen is nights, key
            assert not isinstance(app.screen, AddEntrantDialog | ConfirmDialog | DrawBracketDialog)
        said = notes.text("warning")
        assert "bracket is drawn, so its entrants are set" in said
        assert "has bracket matches still to race; r races the next (W1-1)" in said
        assert "bracket is drawn already; r races its next match" in said


async def test_a_decided_bracket_nights_places_show_at_60x20() -> None:
    """The host walk: at 60x20 the projector of a bracket night showed the standings'
    heading and none of its rows."""
    from dataclasses import replace

    from league.bracket_nights import draw_night_bracket
    from sim.race.rules import HEAD_TO_HEAD_RULES
    from tests.league.test_bracket_nights import race_next

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = qualified_night(league)
        draw_night_bracket(league, night, rules=replace(HEAD_TO_HEAD_RULES, lap_count=1))
        for _ in range(3):
            race_next(league, night, "higher")
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        projector = app.screen
        assert isinstance(projector, NightProjectorScreen)
        await wait_for(pilot, lambda: projector.state is not None)
        await settle(pilot)
        shown = " ".join(painted(projector.query_one("#np-standings")).split())
        assert "Champion: dee" in shown
        assert "Places: 1 dee 25 · 2 cy 18" in shown and "- eve 0" in shown  # all, in a line

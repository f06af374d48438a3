"""A bracket of physical cars in the app: the host draws it from the physical qualifiers,
times each match with a lap key and a reset key per car, and leaves to record it; a match
interrupted by a killed racer-tui comes back."""

from __future__ import annotations

from typing import Any

from textual.pilot import Pilot
from textual.widgets import Input

from league.bracket_records import read_bracket
from league.live_match import live_match_path, read_live_match
from league.opening import open_league
from league.store import default_db_path
from league.timekeeper.journal import journal_path
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.form_select import FormSelect
from racer_tui.app.screens.match_timekeeper import MatchTimekeeperScreen
from racer_tui.app.screens.night_bracket import DrawBracketDialog
from racer_tui.app.screens.nights import NightsScreen
from sim.foundation.home import data_home
from tests.league.test_physical_brackets import physical_night
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.test_timekeeper_screen import Stopwatch
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for


async def draw_physical_bracket(pilot: Pilot[Any], nights: NightsScreen) -> None:
    await pilot.press("k")
    dialog = pilot.app.screen
    assert isinstance(dialog, DrawBracketDialog)
    kind = dialog.query_one("#bracket-kind", FormSelect)
    kind.value = "physical"
    await pilot.pause()
    assert "2 to 4" in painted(dialog.query_one("#bracket-size-label"))
    dialog.query_one("#bracket-size", Input).value = "2"
    dialog.query_one("#bracket-laps", Input).value = "2"
    await pilot.press("ctrl+s")
    await wait_for(pilot, lambda: pilot.app.screen is nights)


async def nine_seconds_in(pilot: Pilot[Any]) -> tuple[MatchTimekeeperScreen, Stopwatch]:
    """The physical bracket drawn on a fresh night and its first match 9 s in."""
    nights = await the_nights_screen(pilot)
    await draw_physical_bracket(pilot, nights)
    keeper, watch = await the_match(pilot)
    await pilot.press("space")
    watch.now += 9.0
    return keeper, watch


async def the_match(pilot: Pilot[Any]) -> tuple[MatchTimekeeperScreen, Stopwatch]:
    await pilot.press("r")
    await wait_for(pilot, lambda: isinstance(pilot.app.screen, MatchTimekeeperScreen))
    keeper = pilot.app.screen
    assert isinstance(keeper, MatchTimekeeperScreen)
    watch = Stopwatch()
    keeper.clock = watch
    return keeper, watch


async def test_a_physical_match_is_timed_for_both_cars_and_recorded() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = physical_night(league)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await draw_physical_bracket(pilot, nights)
        assert "Simulated cars are left out of the bracket (eve, fay are)" in notes.text()

        keeper, watch = await the_match(pilot)
        assert "Final (W1-1): ana v bob" in painted(keeper.query_one("#mt-title"))
        await pilot.press("space")
        watch.now += 4.0
        await pilot.press("w")  # bob off the track: the night's 3 s on his time
        watch.now += 6.0
        await pilot.press("2", "1")  # both cross the line at 10 s
        live = live_match_path(default_db_path(), night.id)
        await wait_for(pilot, lambda: read_live_match(live, night.id) is not None)
        on_air = read_live_match(live, night.id)
        assert on_air is not None and [car.laps for car in on_air.cars] == [1, 1]
        assert on_air.running_order()[0].racer == "ana"  # bob's reset put him behind
        watch.now += 10.0
        await pilot.press("2")  # bob finishes first: 20 s + 2 s
        assert "Car 2: Lap 2" in painted(keeper.query_one("#mt-said"))
        assert keeper.match.phase.value == "running"  # ana still drives her last lap
        watch.now += 1.0
        await pilot.press("1")  # ana: 21 s, no penalty
        said = painted(keeper.query_one("#mt-said"))
        assert "Every car is done" in said and "Esc records the match" in said
        assert "race 0:21.000" in painted(keeper.query_one("#mt-facts-0"))
        await pilot.press("escape")
        await wait_for(pilot, lambda: "Recorded W1-1: ana beat bob." in notes.text())
    with open_league() as league:
        drawn = read_bracket(league, night.id)
        assert drawn is not None and drawn.final_order() is not None
        assert drawn.racers[drawn.final_order()[0]] == "ana"
    assert not journal_path(default_db_path(), f"{night.id}-W1-1").exists()


async def test_a_match_cut_short_by_a_killed_app_resumes_with_its_laps() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        physical_night(league)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, _ = await nine_seconds_in(pilot)
        await pilot.press("1")
        await pilot.press("tab", "u")  # car 2 chosen: it has no lap to take back
        assert "no lap" in painted(keeper.query_one("#mt-said")).lower()
        assert keeper.chosen == 1
    # The app is gone mid-match; the next one offers the match back.
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await the_nights_screen(pilot)
        await pilot.press("r")
        await wait_for(pilot, lambda: isinstance(pilot.app.screen, ConfirmDialog))
        await pilot.press("escape")  # resume: the deliberate key starts it again
        keeper = pilot.app.screen
        assert isinstance(keeper, MatchTimekeeperScreen)
        await settle(pilot)
        assert keeper.match.phase.value == "paused"
        assert [len(heat.laps) for heat in keeper.match.cars] == [1, 0]
        assert "Resumed, paused" in painted(keeper.query_one("#mt-said"))


async def test_a_lap_under_a_question_is_still_a_lap() -> None:
    """The walk: a reset pressed while "Leave this match?" was up was lost; a car crossing
    the line while the host reads a question is still timed."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        physical_night(league)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, _ = await nine_seconds_in(pilot)
        await pilot.press("e")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("1", "w")  # under the question: car 1's lap, car 2's reset
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("n")
        assert app.screen is keeper
        assert len(keeper.match.cars[0].laps) == 1 and keeper.match.cars[1].resets == 1
        # The night's own cost of a reset (its league rules: 3 s), not head-to-head's 2 s.
        assert "3 s added a reset" in painted(keeper.query_one("#mt-state"))


def test_a_decided_bracket_shows_no_gap_to_its_champions_qualifying_lap() -> None:
    """The walk: after bob won the final, ana (quicker in qualifying, placed second)
    showed "+-0.500" on the projector."""
    from rich.console import Console

    from league.bracket_nights import draw_night_bracket, next_match, record_match
    from league.night_state import read_night
    from racer_tui.app.screens.night_projector import standings_table
    from tests.league.test_physical_brackets import MATCH_RULES, timed_match

    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = physical_night(league)
        draw_night_bracket(league, night, size=2, rules=MATCH_RULES, physical=True)
        cars = next_match(league, night)
        assert cars is not None
        record_match(league, night, cars.match.id, timed_match("ana", "bob", "bob"))
        state = read_night(league, night.id)
    console = Console(width=100, record=True)
    console.print(standings_table(state, None, spaced=False))
    shown = console.export_text()
    assert "+-" not in shown
    lines = [line for line in shown.splitlines() if "bob" in line or "ana" in line]
    assert lines[0].split()[:2] == ["1", "bob"] and "+" not in lines[1]


async def test_a_retired_car_forfeits_on_every_screen() -> None:
    """The walk: after f, y the retired car still showed as leading, and the projector
    never said it was out."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = physical_night(league)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, watch = await nine_seconds_in(pilot)
        await pilot.press("1", "f")  # car 1 (the chosen car) a lap up, then out
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await settle(pilot)
        assert "leading: bob" in painted(keeper.query_one("#mt-state"))
        assert painted(keeper.query_one("#mt-facts-0")).startswith("Retired")
        live = live_match_path(default_db_path(), night.id)

        def car_1_on_the_projector() -> str | None:
            match = read_live_match(live, night.id)
            return None if match is None else match.cars[0].held_for

        watch.now += 1.0
        await wait_for(pilot, lambda: car_1_on_the_projector() == "retired")
        await pilot.press("u")  # its laps stand
        assert "Car 1 is retired" in painted(keeper.query_one("#mt-said"))

"""A physical car's heat on a league night, timed with the keyboard and with an automatic
timer's lines: the timekeeper's keys, its clocks, and the result recorded like any heat's."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot
from textual.widgets import Digits

from league.nights import add_entrant, draw_heats, list_nights, new_night, standings
from league.opening import open_league
from league.races import race_result
from league.store import default_db_path
from league.timekeeper.journal import HeatJournal, journal_path
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog
from racer_tui.app.screens.nights import AddEntrantDialog
from racer_tui.app.screens.timekeeper import TimekeeperScreen, TimekeeperSetup, lap_clock_text
from racer_tui.app.widgets.lap_list import LapList
from sim.physics.labels import PHYSICAL
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.racer_tui.screens.test_nights import table_rows, the_nights_screen
from tests.racer_tui.screens.tui_helpers import (
    Notifications,
    OneScreenApp,
    painted,
    settle,
    wait_for,
)


class Stopwatch:
    """The timekeeper's clock, moved by the test."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


async def the_first_heat_started(pilot: Pilot[Any]) -> tuple[TimekeeperScreen, Stopwatch]:
    """The timekeeper of the night's first heat, started (Space) on the test's own clock."""
    await the_nights_screen(pilot)
    await pilot.press("r")
    await settle(pilot)
    keeper = pilot.app.screen
    assert isinstance(keeper, TimekeeperScreen)
    watch = Stopwatch()
    keeper.clock = watch
    await pilot.press("space")
    return keeper, watch


def test_the_lap_clock_shows_tenths() -> None:
    assert lap_clock_text(9.87) == "0:09.8"
    assert lap_clock_text(71.25) == "1:11.2"


async def test_a_physical_cars_heat_is_timed_by_hand_and_recorded_on_the_night() -> None:
    with open_league() as league:
        rules = RaceRules(window_seconds=60.0, penalty_seconds=2.0, max_offtracks_per_lap=3)
        new_night(league, resolve_track("beginner-oval"), rules=rules, name="friday")
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        await pilot.press("a")
        assert isinstance(app.screen, AddEntrantDialog)
        await pilot.press(*"carol", "enter", *"physical:blue car", "enter")
        await settle(pilot)
        await pilot.press("d")
        await settle(pilot)
        assert table_rows(nights, "#heats")[0][2] == "physical: blue car"  # kind first

        await pilot.press("r")
        await settle(pilot)
        keeper = app.screen
        assert isinstance(keeper, TimekeeperScreen)
        assert keeper.setup.car == "blue car"
        watch = Stopwatch()
        keeper.clock = watch
        await pilot.press("l")  # before the start: said, not captured
        assert "start the race first" in str(keeper.said)
        await pilot.press("space")
        watch.now += 3.0
        await pilot.press("r")
        watch.now += 7.0
        await pilot.press("l")  # lap 1: 10 s and one reset (+2 s)
        assert str(keeper.said) == "Lap 1: 12.000 s, counts."
        watch.now += 2.5
        await pilot.pause(0.15)  # the clocks redraw ten times a second
        assert str(keeper.query_one("#tk-lap", Digits).value) == "0:02.5"
        assert str(keeper.query_one("#tk-left", Digits).value) == "0:48"
        for _ in range(4):
            await pilot.press("r")
        assert "over 3, this lap will not count" in str(keeper.said)
        watch.now += 6.5
        await pilot.press("l")  # lap 2: 9 s, but four resets
        laps = keeper.query_one(LapList).rows()
        assert [row[0] for row in laps] == ["1", "2"]
        assert laps[0][4] == "✓" and laps[1][4] == "✗ resets"
        facts = painted(keeper.query_one("#tk-facts"))
        assert "Best 0:12.000" in facts and "1 of 2 laps count" in facts

        await pilot.press("e")
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("y")
        await pilot.pause()
        assert "Race over" in painted(keeper.query_one("#tk-facts"))
        await pilot.press("escape")  # records the heat and goes back
        await settle(pilot)
        assert app.screen is nights
        assert "Recorded carol's heat: best lap 12.000 s." in notes.text()

    with open_league() as league:
        (night,) = list_nights(league)
        (standing,) = standings(league, night)
        assert (standing.entry.racer, standing.entry.score) == ("carol", 12.0)
        result = race_result(league, standing.entry.record_id)
        assert result.physics == PHYSICAL and result.model_name == "blue car"
        assert [(lap.raw_seconds, lap.offtracks, lap.valid) for lap in result.laps] == [
            (10.0, 1, True),
            (9.0, 4, False),  # four resets: over the limit
        ]


async def test_a_lap_count_heat_shows_its_lap_of_the_race_and_ends_at_the_last() -> None:
    with open_league() as league:
        rules = RaceRules(window_seconds=60.0, lap_count=2)
        night = new_night(league, resolve_track("beginner-oval"), rules=rules, name="sprint")
        add_entrant(league, night, "dee", "physical")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, watch = await the_first_heat_started(pilot)
        assert "Lap 1 of 2" in painted(keeper.query_one("#tk-facts"))
        watch.now += 10.0
        await pilot.press("l")
        assert "Lap 2 of 2" in painted(keeper.query_one("#tk-facts"))
        watch.now += 9.0
        await pilot.press("l")  # the last lap: no End key needed
        assert str(keeper.said) == (
            "Lap 2: 9.000 s, counts. 2 laps done: race over. Esc records the heat on the "
            "night (strike a lap out first with x)."
        )  # nothing is on the night until Esc, and the timekeeper is told so
        facts = painted(keeper.query_one("#tk-facts"))
        assert "Race over" in facts and "Lap 3" not in facts
        await pilot.pause(0.15)
        assert str(keeper.query_one("#tk-left", Digits).value) == "0:41"  # stopped at 19 s


async def test_the_lap_chosen_with_the_arrows_is_struck_out_and_a_new_lap_is_chosen() -> None:
    setup = TimekeeperSetup(resolve_track("beginner-oval"), RaceRules(), "eve", "red car")
    keeper = TimekeeperScreen(setup)
    watch = Stopwatch()
    keeper.clock = watch
    app = OneScreenApp(keeper)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("space")
        for _ in range(3):
            watch.now += 10.0
            await pilot.press("l")
        laps = keeper.query_one(LapList)
        assert laps.selected == 2  # the newest lap
        await pilot.press("up", "up", "x")
        assert str(keeper.said) == "Lap 1 struck out."
        assert [row[-1] for row in laps.rows()] == ["struck", "✓", "✓"]
        assert laps.selected == 0  # it stays on the lap struck out
        watch.now += 10.0
        await pilot.press("l")
        assert laps.selected == 3
        shown = painted(laps)
        assert "Lap     Time      Raw Resets Counts" in shown
        assert "  4 0:10.000 0:10.000      0 ✓" in shown


async def test_a_heat_left_by_a_stopped_racer_tui_is_resumed_with_its_laps() -> None:
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "dee", "physical:green car")
        (heat,) = draw_heats(league, night, seed=1)
    journal = journal_path(default_db_path(), heat.id)
    first = create_app(start="league")
    async with first.run_test(size=(80, 24)) as pilot:
        keeper, watch = await the_first_heat_started(pilot)
        watch.now += 11.0
        await pilot.press("r", "l")  # lap 1: 11 s and a reset
        watch.now += 4.0
        await pilot.pause(0.15)  # a heartbeat: the race has run 15 s
    assert journal.exists()  # racer-tui stopped in the middle of the heat

    second = create_app(start="league")
    async with second.run_test(size=(80, 24)) as pilot:
        notes = Notifications(second)
        nights = await the_nights_screen(pilot)
        await pilot.press("r")
        await settle(pilot)
        question = second.screen
        assert isinstance(question, ConfirmDialog)
        asked = " ".join(painted(question.query_one("#question-body")).split())
        assert "racer-tui stopped during this heat, with 3:45 left and 1 lap captured" in asked
        # The question's answers are its buttons: start again from the line (the
        # deliberate y: it throws the timed laps away), or resume, which Esc does too.
        buttons = {str(button.label) for button in question.query("Button")}
        assert buttons == {"Start again (y)", "Resume (n)"}
        await pilot.press("escape")
        await settle(pilot)
        keeper = second.screen
        assert isinstance(keeper, TimekeeperScreen)
        assert [row[1] for row in keeper.query_one(LapList).rows()] == ["0:14.000"]
        assert "Resumed, paused" in str(keeper.said)
        assert str(keeper.query_one("#tk-left", Digits).value) == "3:45"
        watch = Stopwatch()
        keeper.clock = watch
        await pilot.press("space")
        watch.now += 9.0
        await pilot.press("l")  # lap 2: 4 s before the stop and 9 s after
        assert str(keeper.said) == "Lap 2: 13.000 s, counts."
        await pilot.press("e", "y", "escape")
        await settle(pilot)
        assert second.screen is nights
        assert "Recorded dee's heat: best lap 13.000 s." in notes.text()
    assert not journal.exists()  # recorded: nothing left to resume


async def test_a_journal_the_disk_refuses_is_said_once_and_the_timing_goes_on(
    tmp_path: Path,
) -> None:
    (tmp_path / "not-a-folder").write_text("")
    journal = HeatJournal(tmp_path / "not-a-folder" / "heat.json", "01JDR0000000000000000HEAT1")
    setup = TimekeeperSetup(
        resolve_track("beginner-oval"), RaceRules(), "eve", "red car", journal=journal
    )
    keeper = TimekeeperScreen(setup)
    watch = Stopwatch()
    keeper.clock = watch
    app = OneScreenApp(keeper)
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        await pilot.press("space")
        watch.now += 10.0
        await pilot.press("l")
        assert str(keeper.said) == "Lap 1: 10.000 s, counts."
        warnings = notes.text("warning")
        assert warnings.count("This heat's journal cannot be written") == 1
        assert "if racer-tui stops, this heat cannot be resumed" in warnings


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pseudo-terminal")
async def test_an_automatic_timers_lines_start_the_race_and_capture_laps(
    tmp_path: Path,
) -> None:
    from racer_tui.app.screens.timekeeper import TimekeeperSetup

    controller, device = os.openpty()
    setup = TimekeeperSetup(
        track=resolve_track("beginner-oval"),
        rules=RaceRules(window_seconds=60.0),
        racer="dan",
        car="red car",
        timer=os.ttyname(device),
    )
    keeper = TimekeeperScreen(setup)
    watch = Stopwatch()
    keeper.clock = watch
    app = create_app(start="league")
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            await app.push_screen(keeper)
            await pilot.pause()
            os.write(controller, b"lap\r\n")  # the car crosses the line: the race starts
            await wait_for(pilot, lambda: keeper.heat.phase.value == "running")
            watch.now += 11.0
            os.write(controller, b"reset\r\nlap\r\n")
            await wait_for(pilot, lambda: len(keeper.heat.laps) == 1)
            assert (keeper.heat.laps[0].raw_seconds, keeper.heat.laps[0].resets) == (11.0, 1)
            os.write(controller, b"banana\r\n")
            await wait_for(pilot, lambda: "neither 'lap' nor 'reset'" in str(keeper.said))
    finally:
        os.close(controller)
        os.close(device)


async def test_a_lap_that_did_not_finish_is_not_struck_out_in_name_only() -> None:
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "dee", "physical")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, watch = await the_first_heat_started(pilot)
        watch.now += 12.0
        await pilot.press("l")  # lap 1 counts
        watch.now += 5.0
        await pilot.press("f")  # lap 2 did not finish: it never counts
        await pilot.press("x")  # the newest lap is selected
        assert str(keeper.said) == ("Lap 2 did not finish, so it never counts; nothing to strike.")
        assert [row[-1] for row in keeper.query_one(LapList).rows()][-1] == "DNF"


async def test_a_lap_faster_than_a_real_car_can_drive_is_not_captured() -> None:
    track = resolve_track("beginner-oval")
    setup = TimekeeperSetup(track, RaceRules(), "eve", "red car")
    keeper = TimekeeperScreen(setup)
    watch = Stopwatch()
    keeper.clock = watch
    app = OneScreenApp(keeper)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("space")
        floor = keeper.heat.floor_seconds
        assert floor is not None and floor > 2.0  # the shortest loop at a real car's speed
        watch.now += floor - 0.5  # a press mid-lap, past the double-press second
        await pilot.press("l")
        assert "faster than a real car can drive this track" in str(keeper.said)
        assert keeper.query_one(LapList).rows() == []
        watch.now += 10.0
        await pilot.press("l")
        assert len(keeper.query_one(LapList).rows()) == 1  # the lap goes on and is captured


async def test_two_physical_cars_stay_apart_in_a_narrow_heats_table() -> None:
    # Issue 42, point 8 (walk at 60x20): both cars were cut to "physical…".
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "bartholomew", "physical:blue car 1")
        add_entrant(league, night, "carolina", "physical:blue car 2")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        nights = await the_nights_screen(pilot)
        cars = [row[2] for row in table_rows(nights, "#heats")]
        # "phys…ar 1": the kind at the front and the car's own end both stay.
        assert len(set(cars)) == 2, cars
        assert sorted(car[-1] for car in cars) == ["1", "2"]
        assert all(car.startswith("phys") for car in cars)


async def test_the_timekeeper_at_60x20_says_each_lap_and_refusal_whole() -> None:
    # The host walk at 60x20: "struck out" wrapped "out" onto a line that read as a fourth
    # lap, and a too-fast lap's sentence lost its end ("…not captured; capture").
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "zed", "physical")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        keeper, watch = await the_first_heat_started(pilot)
        watch.now += 2.0  # quicker than a real car can lap the oval
        await pilot.press("l")
        await settle(pilot)
        said = " ".join(painted(keeper.query_one("#tk-said")).split())
        assert said.endswith("capture when the car crosses the line.")
        watch.now += 9.0
        await pilot.press("l", "x")
        await settle(pilot)
        shown = [line for line in painted(keeper.query_one(LapList)).splitlines() if line.strip()]
        assert len(shown) == 2 and shown[1].rstrip().endswith("struck")  # header, lap 1


async def test_quitting_in_the_middle_of_a_timed_heat_is_asked() -> None:
    """The host walk: Ctrl+Q in the timekeeper quit at once, while Esc asked."""
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), name="friday")
        add_entrant(league, night, "dee", "physical:green car")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    quits: list[bool] = []
    app.exit = lambda *args, **kwargs: quits.append(True)  # type: ignore[method-assign]
    async with app.run_test(size=(80, 24)) as pilot:
        keeper, _watch = await the_first_heat_started(pilot)
        await pilot.press("ctrl+q")
        await settle(pilot)
        question = app.screen
        assert isinstance(question, ConfirmDialog)
        asked = " ".join(painted(question.query_one("#question-body")).split())
        assert asked.startswith("A physical car's heat is being timed; its laps are kept")
        await pilot.press("escape")  # keep racing
        await settle(pilot)
        assert app.screen is keeper and not quits
        await pilot.press("ctrl+q", "y")
        await settle(pilot)
        assert quits

"""A league night on the venue's screen: the heat running now (from the file its screen
writes), the night's standings with points and gaps, the newest result highlighted for a
while, and the final standings once the night closes."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Digits

from league.live_heat import STALE_SECONDS, LiveHeatWriter, live_heat_path
from league.live_match import LiveCar, LiveIncident, LiveMatchWriter, live_match_path
from league.nights import (
    Night,
    add_entrant,
    close_night,
    delete_night,
    draw_heats,
    heats,
    new_night,
)
from league.opening import open_league
from league.races import record_race
from league.store import default_db_path
from racer_tui.app.application import create_app
from racer_tui.app.screens.head_to_head_screen import car_colour
from racer_tui.app.screens.night_projector import HIGHLIGHT_SECONDS, NightProjectorScreen, ordinal
from racer_tui.app.widgets.race_map import RaceMap
from sim.foundation.home import data_home
from sim.physics.labels import PHYSICAL
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle

RULES = RaceRules(window_seconds=120.0, penalty_seconds=2.0, max_offtracks_per_lap=3)
LAPS = {"ana": [12.0, 11.5], "[b]bob[/b]": [10.5], "cy": [13.0]}


class Clock:
    def __init__(self) -> None:
        self.now = 5000.0

    def __call__(self) -> float:
        return self.now


def a_night_with_one_heat_raced() -> Night:
    """Three entrants (bob drives a physical car), drawn; the first heat raced."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), rules=RULES, name="friday")
        add_entrant(league, night, "ana", "reference")
        add_entrant(league, night, "[b]bob[/b]", "physical:blue car")
        add_entrant(league, night, "cy", "reference")
        draw_heats(league, night, seed=11)
        record_heat(league, night, 0)
    return night


def record_heat(league: Any, night: Night, index: int) -> str:
    heat = heats(league, night)[index]
    racer = heat.entrant.racer
    result = race_result(racer, LAPS[racer], rules=RULES, track=resolve_track("beginner-oval"))
    if racer == "[b]bob[/b]":
        result = replace(result, physics=PHYSICAL, model_name="blue car")
    record_race(league, result, night.id, heat_id=heat.id)
    return racer


def on_air(night: Night, clock: Clock, *, heat_index: int) -> LiveHeatWriter:
    with open_league() as league:
        heat = heats(league, night)[heat_index]
    writer = LiveHeatWriter(
        live_heat_path(default_db_path(), night.id),
        night_id=night.id,
        heat_id=heat.id,
        heat_number=heat_index + 1,
        racer=heat.entrant.display_name,
        car="blue car",
    )
    writer.publish(
        state="running",
        time_left=95.2,
        lap=3,
        lap_time=4.25,
        best_lap=10.5,
        offtracks=1,
        limit=3,
        now=clock.now,
    )
    return writer


async def the_projector(pilot: Pilot[Any], clock: Clock) -> NightProjectorScreen:
    """The projector the app started on, on the test's clock."""
    await settle(pilot)
    screen = pilot.app.screen
    assert isinstance(screen, NightProjectorScreen)
    screen.clock = clock
    return screen


async def test_the_projector_follows_a_night_from_heat_to_heat() -> None:
    night = a_night_with_one_heat_raced()
    with open_league() as league:
        first = heats(league, night)[0].entrant.display_name
    clock = Clock()
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await the_projector(pilot, clock)
        assert "friday · beginner-oval · ranked by best lap" in painted(
            screen.query_one("#np-title")
        )
        now = painted(screen.query_one("#np-heat"))
        assert "Next up: heat 2 of 3" in now
        standings = painted(screen.query_one("#np-standings"))
        assert first in standings and "25" in standings  # the first heat's points
        assert screen.news is None  # a result already there when it opened is not news

        # The next heat starts in the host's racer-tui: the projector shows it running.
        writer = on_air(night, clock, heat_index=1)
        screen._read_live()
        await pilot.pause()
        now = painted(screen.query_one("#np-heat"))
        with open_league() as league:
            second = heats(league, night)[1].entrant.display_name
        assert "Racing now: heat 2 of 3" in now and second in now
        assert "Lap 3  0:04.2" in now and "off 1/3" in now and "best 0:10.500" in now

        # It ends: recorded, and the file is gone. The result is news for a while.
        with open_league() as league:
            racer = record_heat(league, night, 1)
        writer.clear()
        screen._read_live()
        await settle(pilot)
        assert screen.highlight == racer
        news = painted(screen.query_one("#np-news"))
        assert f"New result: {second}, best lap" in news
        rows = painted(screen.query_one("#np-standings"))
        ranks = [line.split()[0] for line in rows.splitlines()[2:] if line.strip()]
        assert ranks == ["1", "2"]  # one rank per racer, never two 1s
        assert "+" in rows  # the gap to the leader

        clock.now += HIGHLIGHT_SECONDS
        screen._read_live()
        await pilot.pause()
        assert screen.highlight is None and painted(screen.query_one("#np-news")).strip() == ""

        # A racer-tui killed mid-heat leaves its file behind: stale, it is no heat.
        on_air(night, clock, heat_index=2)
        clock.now += STALE_SECONDS + 1
        screen._read_live()
        await pilot.pause()
        assert "Next up: heat 3 of 3" in painted(screen.query_one("#np-heat"))

        with open_league() as league:
            record_heat(league, night, 2)
            close_night(league, night, "host")
        screen.action_refresh_now()
        await settle(pilot)
        assert "final standings" in painted(screen.query_one("#np-title"))
        assert "The night is over" in painted(screen.query_one("#np-heat"))
        rows = painted(screen.query_one("#np-standings"))
        assert "[b]bob[/b]" in rows and "blue car" in rows  # names are plain text
        assert [line.split()[-1] for line in rows.splitlines()[2:] if line.strip()] == [
            "25",
            "18",
            "15",
        ]
        await pilot.press("escape")  # a kiosk: Esc does nothing
        assert isinstance(app.screen, NightProjectorScreen)
        assert app.return_code is None
        await pilot.press("q", "y")  # leaving asks first; started alone, it quits
        assert app.return_code == 0


def test_places_read_as_places() -> None:
    assert [ordinal(place) for place in (1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 111)] == [
        "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd", "111th",
    ]  # fmt: skip


async def test_a_night_deleted_under_the_projector_is_said_once_on_screen() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), rules=RULES, name="oops")
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, NightProjectorScreen)
        assert "No heats yet" in painted(screen.query_one("#np-heat"))
        with open_league() as league:
            delete_night(league, night, "host")
        screen.action_refresh_now()
        await settle(pilot)
        screen._read_live()
        await pilot.pause()
        shown = painted(screen.query_one("#np-heat"))
        assert "This night cannot be shown: the night is no longer in the league" in " ".join(
            shown.split()
        )
        assert notes.messages == []  # no error notification every two seconds


async def test_a_lap_count_night_says_so_and_shows_the_lap_of_the_race() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        rules = replace(RULES, lap_count=5)
        night = new_night(league, resolve_track("beginner-oval"), rules=rules, name="sprint")
        add_entrant(league, night, "ana", "reference")
        draw_heats(league, night, seed=1)
    clock = Clock()
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await the_projector(pilot, clock)
        title = painted(screen.query_one("#np-title"))
        assert "sprint · beginner-oval · 5-lap race · ranked by best lap" in title
        on_air(night, clock, heat_index=0)
        screen._read_live()
        await pilot.pause()
        assert "Lap 3 of 5  0:04.2" in painted(screen.query_one("#np-heat"))


async def test_a_night_of_physical_cars_names_them_without_marking_each() -> None:
    """'(physical)' tells physical cars from simulated ones on a mixed night; on a night of
    physical cars only it would be on every row and cut the cars' names at 80 columns."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track("beginner-oval"), rules=RULES, name="garage")
        add_entrant(league, night, "ana", "physical:red racer")
        add_entrant(league, night, "cy", "physical:green machine")
        for heat in draw_heats(league, night, seed=3):
            racer = heat.entrant.racer
            car = "red racer" if racer == "ana" else "green machine"
            result = race_result(racer, LAPS[racer], rules=RULES)
            result = replace(result, physics=PHYSICAL, model_name=car)
            record_race(league, result, night.id, heat_id=heat.id)
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await the_projector(pilot, Clock())
        rows = painted(screen.query_one("#np-standings"))
        assert "red racer" in rows and "green machine" in rows
        assert "physical" not in rows


async def test_a_bracket_match_is_shown_as_it_is_raced() -> None:
    night = a_night_with_one_heat_raced()
    clock = Clock()
    live = LiveMatchWriter(
        live_match_path(default_db_path(), night.id),
        night_id=night.id,
        match_id="W1-1",
        title="Final",
        lap_count=3,
        racers=[("ana", "reference"), ("[b]bob[/b]", "rival.racer-bundle")],
    )
    app = create_app(start="league", projector_night=night.id)
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await the_projector(pilot, clock)
        ana = LiveCar("", "", 2, 1, 0.84, "crash", False, (0.5, 0.3), 90.0)
        bob = LiveCar("", "", 1, 2, None, "", False, (0.0, -1.0), 0.0)
        crash = LiveIncident(74.9, "crash", 0, 1)
        live.publish(state="running", clock=75.0, cars=[ana, bob], incidents=[crash], now=clock.now)
        screen._read_live()
        await pilot.pause()
        now = painted(screen.query_one("#np-heat"))
        assert "Racing now: Final (W1-1)" in now
        assert "1:14 ana ran into [b]bob[/b] and is held" in now
        # The cars on the track in the standings' place, in the race view's colours.
        drawn = screen.query_one("#np-map", RaceMap)
        assert screen.has_class("-match-on-air") and drawn.display
        assert not screen.query_one("#np-standings").display
        assert [car.colour for car in drawn._cars] == [car_colour(0), car_colour(1)]
        assert drawn._cars[0].held and not drawn._cars[1].held
        lines = [line.strip() for line in now.splitlines()]
        leader = next(i for i, line in enumerate(lines) if "[b]bob[/b]" in line)
        assert lines[leader].startswith("1 ■ [b]bob[/b]") and "laps 2/3" in lines[leader]
        assert "+0.84 s" in lines[leader + 1] and "crash" in lines[leader + 1]
        assert screen.query_one("#np-clock", Digits).value == "1:15"  # the race clock, 75 s
        live.publish(state="over", clock=90.0, cars=[ana, bob], now=clock.now + 1)
        screen._read_live()
        await pilot.pause()
        assert "Just finished: Final" in painted(screen.query_one("#np-heat"))
        assert not screen.has_class("-match-on-air")  # the bracket and standings again
        live.clear()
        screen._read_live()
        await pilot.pause()
        assert "Final" not in painted(screen.query_one("#np-heat"))  # back to the night

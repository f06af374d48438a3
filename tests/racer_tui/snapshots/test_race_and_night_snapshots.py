"""SVG snapshots of the race view (a recorded race replayed to its end, with the ghost of
its best lap), of the host's league-night screen part-way through a night (two heats
drawn, one raced) and of the timekeeper part-way through a physical car's heat. Races
are deterministic, so the laps, times and standings are fixed.
Update after a deliberate change with
`pytest tests/racer_tui/snapshots/test_race_and_night_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from datetime import date
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Select

from league.nights import add_entrant, draw_heats, new_night, run_heats
from league.opening import open_league
from racer_tui.app.application import create_app
from racer_tui.app.screens.head_to_head_screen import HeadToHeadScreen, HeadToHeadSetup
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.screens.timekeeper import TimekeeperScreen, TimekeeperSetup
from sim.foundation.home import data_home
from sim.race.driver import reference_driver
from sim.race.engine import run_race
from sim.race.head_to_head import Entry
from sim.race.replay import ghost_lap
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.drivers import resolve_driver
from tests.racer_tui.screens.tui_helpers import OneScreenApp, settle, wait_for
from tests.racer_tui.snapshots.sizes import SIZES

FRIDAY = date(2026, 3, 6)  # a fixed day: the screens show it

Compare = Callable[..., bool]
SHORT = RaceRules(window_seconds=30.0)


@SIZES
def test_race_view_at_the_end_of_a_replay(snap_compare: Compare, size: tuple[int, int]) -> None:
    track = resolve_track("hairpin-circuit")
    recorded = run_race(track, SHORT, racer="[b]Ada[/b]")
    setup = RaceSetup(
        track=track, rules=SHORT, racer="[b]Ada[/b]", replay=recorded, ghost=ghost_lap(recorded)
    )

    async def to_the_end(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("e")
        await settle(pilot)

    app = OneScreenApp(RaceScreen(setup))
    assert snap_compare(app, terminal_size=size, run_before=to_the_end)


@SIZES
def test_league_night_part_way(snap_compare: Compare, size: tuple[int, int]) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, oval, rules=SHORT, name="friday", held_on=FRIDAY)
        add_entrant(league, night, "ada", "reference")
        add_entrant(league, night, "[b]bob[/b]", "reference")
        draw_heats(league, night, seed=7)
        run_heats(league, night, oval, resolve_driver, limit=1)

    async def open_nights(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=open_nights)


@SIZES
def test_timekeeper_part_way(snap_compare: Compare, size: tuple[int, int]) -> None:
    """Three laps of a physical car, one over the resets limit, 4.2 s into the fourth."""
    setup = TimekeeperSetup(
        track=resolve_track("reinvent_base"),
        rules=RaceRules(penalty_seconds=0.0),
        racer="[b]Ada[/b]",
        car="blue car",
        title="Heat 2: [b]Ada[/b], blue car",
    )
    keeper = TimekeeperScreen(setup)
    moments = iter([0.0, 9.8, 9.8, 20.2, 20.2, 20.2, 20.2, 20.2, 31.2])

    async def laps(pilot: Pilot[Any]) -> None:
        for key in ("space", "l", "r", "l", "r", "r", "r", "r", "l"):
            now = next(moments)
            keeper.clock = lambda now=now: now
            await pilot.press(key)
        keeper.clock = lambda: 35.4
        await pilot.pause(0.2)  # the clocks redraw at 10 Hz

    assert snap_compare(OneScreenApp(keeper), terminal_size=size, run_before=laps)


@SIZES
def test_match_timekeeper_part_way(snap_compare: Compare, size: tuple[int, int]) -> None:
    """A physical bracket match, both cars a lap done (car 2 with a reset), 3.3 s into the
    second; car 2's laps chosen."""
    from league.timekeeper.match import MatchCar
    from racer_tui.app.screens.match_timekeeper import (
        MatchTimekeeperScreen,
        MatchTimekeeperSetup,
    )

    setup = MatchTimekeeperSetup(
        track=resolve_track("reinvent_base"),
        rules=replace(HEAD_TO_HEAD_RULES, lap_count=2),
        cars=(MatchCar("[b]Ada[/b]", "red", "physical-red"), MatchCar("bo", "blue", "p-b")),
        names=("[b]Ada[/b]", "bo"),
        title="Final (W1-1)",
    )
    keeper = MatchTimekeeperScreen(setup)
    moments = iter([0.0, 4.0, 10.0, 12.0, 12.0])

    async def laps(pilot: Pilot[Any]) -> None:
        for key in ("space", "w", "1", "2", "tab"):
            now = next(moments)
            keeper.clock = lambda now=now: now
            await pilot.press(key)
        keeper.clock = lambda: 13.3
        await pilot.pause(0.2)  # the clocks redraw at 10 Hz

    assert snap_compare(OneScreenApp(keeper), terminal_size=size, run_before=laps)


@SIZES
def test_night_projector_with_a_heat_running(snap_compare: Compare, size: tuple[int, int]) -> None:
    """Two heats raced, the second just now (highlighted), the third on the track."""
    from tests.racer_tui.screens.test_night_projector import (
        Clock,
        a_night_with_one_heat_raced,
        on_air,
        record_heat,
    )

    night = a_night_with_one_heat_raced()
    clock = Clock()

    async def a_result_then_a_heat(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        screen = pilot.app.screen
        assert isinstance(screen, NightProjectorScreen)
        screen.clock = clock
        with open_league() as league:
            record_heat(league, night, 1)
        screen.action_refresh_now()
        await settle(pilot)
        on_air(night, clock, heat_index=2)
        screen._read_live()
        await pilot.pause()

    app = create_app(start="league", projector_night=night.id)
    assert snap_compare(app, terminal_size=size, run_before=a_result_then_a_heat)


@SIZES
def test_head_to_head_at_its_end(snap_compare: Compare, size: tuple[int, int]) -> None:
    """Three reference drivers, two laps: the finish, the order with gaps, the incidents."""
    track = resolve_track("reinvent_base")
    names = ("[b]Ada[/b]", "bob", "cy")

    def entries() -> list[Entry]:
        driver = reference_driver(track)
        return [Entry(name, driver) for name in names]

    setup = HeadToHeadSetup(
        track=track,
        rules=replace(HEAD_TO_HEAD_RULES, lap_count=2),
        names=names,
        entries=entries,
    )
    view = HeadToHeadScreen(setup)

    async def to_the_end(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("e")
        await wait_for(pilot, lambda: view.at_end)
        await settle(pilot)

    assert snap_compare(OneScreenApp(view), terminal_size=size, run_before=to_the_end)


@SIZES
def test_head_to_head_dialog(snap_compare: Compare, size: tuple[int, int]) -> None:
    async def ask(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        pilot.app.screen.query_one("#race-type", Select).value = "head-to-head"
        await pilot.pause()
        await pilot.press("s")
        await settle(pilot)

    assert snap_compare(create_app(start="races"), terminal_size=size, run_before=ask)

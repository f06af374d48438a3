"""SVG snapshots of the race view (a recorded race replayed to its end, with the ghost of
its best lap) and of the host's league-night screen part-way through a night (two heats
drawn, one raced). Races are deterministic, so the laps, times and standings are fixed.
Update after a deliberate change with
`pytest tests/racer_tui/snapshots/test_race_and_night_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from textual.app import App
from textual.pilot import Pilot

from league.nights import add_entrant, draw_heats, new_night, run_heats
from league.store import open_league
from racer_tui.app import create_app
from racer_tui.race_commands import resolve_driver
from racer_tui.screens.race_screen import RaceScreen, RaceSetup
from sim.home import data_home
from sim.race.engine import run_race
from sim.race.replay import ghost_lap
from sim.race.rules import RaceRules
from sim.track_catalog import resolve_track
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

Compare = Callable[..., bool]
SHORT = RaceRules(window_seconds=30.0)


class ReplayApp(App[None]):
    def __init__(self, screen: RaceScreen) -> None:
        super().__init__()
        self.race = screen

    def on_mount(self) -> None:
        self.push_screen(self.race)


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

    app = ReplayApp(RaceScreen(setup))
    assert snap_compare(app, terminal_size=size, run_before=to_the_end)


@SIZES
def test_league_night_part_way(snap_compare: Compare, size: tuple[int, int]) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, oval, rules=SHORT, name="friday")
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

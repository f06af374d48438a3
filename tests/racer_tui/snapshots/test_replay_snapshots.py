"""SVG snapshot of the Races section's recorded races at 80x24: a night's race and a
time trial with their traces (replayable), and one without (dim), at fixed times.
Update after a deliberate change with
`pytest tests/racer_tui/snapshots/test_replay_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from datetime import date
from typing import Any

from textual.pilot import Pilot

from league.nights import new_night
from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from sim.foundation.home import data_home
from sim.race.engine import run_race
from sim.race.rules import DEFAULT_RULES, RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES

FRIDAY = date(2026, 3, 6)  # a fixed day: the screens show it

Compare = Callable[..., bool]


def recorded_races() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, oval, name="friday", held_on=FRIDAY)
        record_race(
            league,
            race_result("bob", [14.0, 13.2], model="bolt", started_at="2024-04-30T18:00:00.000Z"),
        )
        trial = run_race(oval, RaceRules(window_seconds=20.0), racer="[b]ada[/b]")
        record_race(league, replace(trial, started_at="2024-05-01T19:00:00.000Z"))
        heat = run_race(oval, DEFAULT_RULES, racer="cy", seed=3)
        record_race(league, replace(heat, started_at="2024-05-03T20:15:00.000Z"), night.id)


async def _settled(pilot: Pilot[Any]) -> None:
    await settle(pilot)


@SIZES
def test_recorded_races(snap_compare: Compare, size: tuple[int, int]) -> None:
    recorded_races()
    app = create_app(start="races")
    assert snap_compare(app, terminal_size=size, run_before=_settled)

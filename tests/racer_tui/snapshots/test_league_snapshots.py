"""SVG snapshots of the League section and the projector at 80x24 and 120x40, with fixed
race results (fixed times and dates; ids are never shown), of the section on a board
of another race type than time trials, and of its head-to-head board at 80x24 and 60x20.
Update after a deliberate change with
`pytest tests/racer_tui/snapshots/test_league_snapshots.py --snapshot-update`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from textual.pilot import Pilot

from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from sim.foundation.home import data_home
from sim.tracks.catalog import resolve_track
from tests.league.helpers import head_to_head_in_order, race_result
from tests.racer_tui.screens.tui_helpers import settle
from tests.racer_tui.snapshots.sizes import SIZES, SMALL, TINY

Compare = Callable[..., bool]


def fixed_results() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    hairpin = resolve_track("hairpin-circuit")
    with open_league() as league:
        record_race(league, race_result("ada", [12.0, 11.5, 11.8], model="ada-car"))
        record_race(league, race_result("bob", [11.0, 13.0], offtracks=[0, 2], model="bolt"))
        record_race(league, race_result("[b]cy[/b]", [12.9], model="slow-and-steady"))
        record_race(league, race_result("dee", [20.0], track=hairpin, model="hairpin-hero"))


async def _settled(pilot: Pilot[Any]) -> None:
    await settle(pilot)


@SIZES
def test_leaderboard(snap_compare: Compare, size: tuple[int, int]) -> None:
    fixed_results()
    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=_settled)


@SIZES
def test_projector(snap_compare: Compare, size: tuple[int, int]) -> None:
    fixed_results()

    async def project(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("p")
        await settle(pilot)

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=project)


@SIZES
def test_leaderboard_of_another_race_type(snap_compare: Compare, size: tuple[int, int]) -> None:
    """The oval raced among boxes too: t shows its object-avoidance board."""
    from sim.race.rules import preset_rules

    fixed_results()
    with open_league() as league:
        boxes = preset_rules("object-avoidance")
        record_race(league, race_result("eve", [14.0, 13.5], model="box-dodger", rules=boxes))
        record_race(league, race_result("ada", [15.25], model="ada-car", rules=boxes))

    async def switch(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("t")
        await settle(pilot)

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=switch)


@pytest.mark.parametrize("size", [SMALL, TINY], ids=["80x24", "60x20"])
def test_head_to_head_board(snap_compare: Compare, size: tuple[int, int]) -> None:
    """Four head-to-head races on the oval at fixed times (real cars' laps, renamed): t
    shows the board, bob highlighted so the detail is his record against each rival."""
    from league.head_to_heads import record_head_to_head
    from tests.league.sync.leagues import head_to_head

    fixed_results()
    cars = head_to_head("x", "y", "z", seed=1)
    with open_league() as league:
        for minute, racers, models in (
            (0, ("ada", "bob"), ("ada-car", "bolt")),
            (10, ("bob", "ada"), ("bolt-2", "ada-car")),
            (20, ("bob", "[b]cy[/b]", "ada"), ("bolt-2", "slow-and-steady", "ada-car")),
            (30, ("ada", "bob"), ("ada-car", "bolt-2")),
        ):
            race = head_to_head_in_order(
                cars, *racers, models=models, started_at=f"2026-03-06T19:{minute:02}:00.000Z"
            )
            record_head_to_head(league, race)

    async def switch(pilot: Pilot[Any]) -> None:
        await settle(pilot)
        await pilot.press("t")
        await settle(pilot)
        await pilot.press("down")
        await settle(pilot)

    app = create_app(start="league")
    assert snap_compare(app, terminal_size=size, run_before=switch)

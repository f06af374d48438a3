"""Race types in the app: the League section shows one race type's boards at a time, says
which when the league has laps of another, and t switches between the race types with laps
on the chosen track; the Nights screen and the night projector say a night's race type."""

from __future__ import annotations

import json
from pathlib import Path

from textual.widgets import Input, Select

from league.nights import add_entrant, draw_heats, new_night
from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.widgets.footer import RacerFooter
from sim.foundation.home import data_home
from sim.race.rules import preset_rules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.tui_helpers import painted, settle

BOXES = preset_rules("object-avoidance")
HAIRPIN = "hairpin-circuit"


def mixed_league() -> None:
    """The oval's time trials (ana leads) and object-avoidance races (cy, quicker than
    anyone, leads), and a time trial on the hairpin."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ana", [10.0], model="ana-car"))
        record_race(league, race_result("bex", [11.0], model="bex-car"))
        record_race(league, race_result("cy", [9.0], rules=BOXES, model="cy-car"))
        record_race(league, race_result("bex", [12.5], rules=BOXES, model="bex-car"))
        record_race(league, race_result("dee", [20.0], track=resolve_track(HAIRPIN)))


def board(screen: LeagueScreen) -> list[tuple[str, int, str]]:
    return [(row.racer, row.rank, row.race_type) for row in screen.rows]


def line(screen: LeagueScreen) -> str:
    return painted(screen.query_one("#board-race-type")).strip()


def footer(screen: LeagueScreen) -> str:
    return painted(screen.query_one(RacerFooter))


async def test_a_time_trial_and_an_object_avoidance_race_rank_on_separate_boards() -> None:
    mixed_league()
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        # Every track's time trials: cy's lap among boxes is on no board here.
        assert board(screen) == [
            ("ana", 1, "time_trial"),
            ("bex", 2, "time_trial"),
            ("dee", 1, "time_trial"),
        ]
        assert line(screen) == "Time trial boards  ·  t switches to object avoidance"
        assert "t Race type" in footer(screen)

        await pilot.press("t")
        await settle(pilot)
        assert board(screen) == [("cy", 1, "object_avoidance"), ("bex", 2, "object_avoidance")]
        assert line(screen) == "Object avoidance boards  ·  t switches to time trial"
        table = painted(screen.query_one("#board"))
        assert "cy-car" in table and "(object avoidance)" not in table  # the line says it

        # The oval chosen: still its object-avoidance board, the host's choice.
        track = screen.query_one("#filter-track", Select)
        track.value = resolve_track(TRACK).content_hash
        await settle(pilot)
        assert [racer for racer, _, _ in board(screen)] == ["cy", "bex"]
        # The hairpin has only time trials: its board, no line and no t.
        track.value = resolve_track(HAIRPIN).content_hash
        await settle(pilot)
        assert board(screen) == [("dee", 1, "time_trial")]
        assert line(screen) == ""
        assert "Race type" not in footer(screen)
        # Back on the oval, the object-avoidance board again; t goes back to time trials.
        track.value = resolve_track(TRACK).content_hash
        await settle(pilot)
        assert [racer for racer, _, _ in board(screen)] == ["cy", "bex"]
        await pilot.press("t")
        await settle(pilot)
        assert [racer for racer, _, _ in board(screen)] == ["ana", "bex"]


async def test_a_league_of_time_trials_shows_no_race_type_at_all() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ana", [10.0]))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        assert line(screen) == "" and "Race type" not in footer(screen)
        await pilot.press("t")  # nothing to switch to: nothing happens
        await settle(pilot)
        assert board(screen) == [("ana", 1, "time_trial")]


async def test_a_track_raced_only_among_boxes_shows_that_board(tmp_path: Path) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("cy", [9.0], rules=BOXES))
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        assert board(screen) == [("cy", 1, "object_avoidance")]
        assert line(screen) == "Object avoidance boards  (no other race type has laps here)"
        # The export is the board shown, its rows naming their race type.
        target = tmp_path / "boxes.json"
        await pilot.press("x")
        await settle(pilot)
        app.screen.query_one(Input).value = str(target)
        await pilot.press("enter")
        await settle(pilot)
    rows = json.loads(target.read_text())
    assert [(row["racer"], row["race_type"]) for row in rows] == [("cy", "object_avoidance")]
    assert rows[0]["track"] == f"{TRACK} (object avoidance)"


async def test_the_nights_screen_and_projector_say_an_object_avoidance_nights_race_type() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track(TRACK), rules=BOXES, name="boxes")
        add_entrant(league, night, "ana", "reference")
        draw_heats(league, night, seed=1)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        nights = await the_nights_screen(pilot)
        shown = " ".join(painted(nights.query_one("#night-rules")).split())  # wrapped at 80
        assert "Rules (frozen): object avoidance (3 boxes): 4:00 window" in shown
        await pilot.press("p")
        await settle(pilot)
        projector = app.screen
        assert isinstance(projector, NightProjectorScreen)
        title = painted(projector.query_one("#np-title"))
        assert "boxes · beginner-oval · object avoidance (3 boxes) · ranked by best lap" in title

"""Issue 42, points 8 and 9: at 80x24 and 60x20 the columns that matter (the board, the
car's kind, the model) stay, a board's name keeps what tells it from another, and the
header's tabs read whole."""

from __future__ import annotations

import csv
import re
from dataclasses import replace
from pathlib import Path

import pytest
from textual.widgets import DataTable, Input, Select

from league.nights import add_entrant, close_night, draw_heats, new_night, run_heats
from league.opening import open_league
from league.races import record_race
from league.seasons import new_season, parse_points
from racer_tui.app.application import create_app
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, _shortened, fit_widths
from sim.foundation.home import data_home
from sim.physics.labels import PHYSICAL
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.drivers import resolve_driver
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import painted, settle


def a_league_with_a_physical_board() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(
            league,
            race_result("Alexandra Montgomery-Fitzgerald", [12.0, 11.5], model="reinvent_base"),
        )
        physical = race_result("dana", [6.35, 6.5], model="reinvent_base")
        record_race(league, replace(physical, physics=PHYSICAL, model_name="reinvent_base"))


@pytest.mark.parametrize("size", [(80, 24), (60, 20)], ids=["80x24", "60x20"])
async def test_the_league_table_keeps_board_and_model_when_narrow(size: tuple[int, int]) -> None:
    a_league_with_a_physical_board()
    app = create_app(start="league")
    async with app.run_test(size=size) as pilot:
        await settle(pilot)
        table = app.screen.query_one("#board", DataTable)
        headers = [str(column.label) for column in table.columns.values()]
        assert any(h.startswith("model") for h in headers)
        assert any(h.startswith("track") for h in headers)
        shown = painted(table)
        assert "(physical)" in shown  # the second rank 1 says which board it leads
        assert table.virtual_size.width <= table.scrollable_content_region.width
        assert "5 League" in painted(app.screen.query_one(SectionHeader))


@pytest.mark.parametrize("size", [(80, 24), (60, 20)], ids=["80x24", "60x20"])
async def test_a_chosen_track_filter_stays_on_one_line(size: tuple[int, int]) -> None:
    # The host walk: "beginner-oval" chosen read "beginner-ova" over "l", a row the board lost.
    a_league_with_a_physical_board()
    app = create_app(start="league")
    async with app.run_test(size=size) as pilot:
        await settle(pilot)
        track = app.screen.query_one("#filter-track", Select)
        rows_before = app.screen.query_one("#board", DataTable).region.y
        track.value = next(value for label, value in track._options if label == "beginner-oval")
        await settle(pilot)
        label = [line for line in painted(track).splitlines() if line.strip(" ▊▎▔▁")]
        assert len(label) == 1 and "beginner-ov" in label[0] and "…" in label[0]
        assert app.screen.query_one("#board", DataTable).region.y == rows_before


async def test_a_hand_timed_race_is_marked_physical_in_the_recorded_races_at_80x24() -> None:
    # Issue 42's walk: at 80x24 the recorded races dropped the track column, and with it
    # the only sign that a lap was a physical car's, timed by hand. (At 60x20 the list
    # keeps when, who and the best lap only, and marks the lap: the test below.)
    a_league_with_a_physical_board()
    app = create_app(start="races")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        table = app.screen.query_one("#recorded-races", DataTable)
        assert table.row_count == 2
        shown = painted(table)
        assert "(physical)" in shown and shown.count("(physical)") == 1
        assert table.virtual_size.width <= table.scrollable_content_region.width


async def test_a_hand_timed_race_is_marked_in_the_recorded_races_at_60x20() -> None:
    # The walk at 60x20: the track column goes, and a hand-timed 6.35 s looked like a
    # simulated lap. It carries a mark instead, and the title says what the mark means.
    a_league_with_a_physical_board()
    app = create_app(start="races")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        table = app.screen.query_one("#recorded-races", DataTable)
        rows = painted(table).splitlines()
        [hand] = [row for row in rows if "dana" in row]
        [simulated] = [row for row in rows if "Alexa" in row]
        assert "6.350 s*" in hand and "*" not in simulated
        assert "(* by hand)" in painted(app.screen.query_one("#recorded-title"))
        assert table.virtual_size.width <= table.scrollable_content_region.width
        await pilot.resize_terminal(100, 30)  # the track column is back: no mark, no note
        await settle(pilot)
        assert "*" not in painted(table) and "(physical)" in painted(table)
        assert "by hand" not in painted(app.screen.query_one("#recorded-title"))


def two_nights_of_a_season() -> None:
    """A closed night of three heats in a season, and a second night whose name starts the
    same."""
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    rules = RaceRules(window_seconds=20.0)
    with open_league() as league:
        new_season(league, "spring", parse_points("10,6,4"))
        night = new_night(league, oval, rules=rules, name="Walk night 2", season="spring")
        for racer in ("ana", "bob", "cy"):
            add_entrant(league, night, racer, "reference")
        draw_heats(league, night, seed=1)
        run_heats(league, night, oval, resolve_driver)
        close_night(league, night, "host")
        new_night(league, oval, rules=rules, name="Walk night 3")


async def test_a_night_at_60x20_tells_its_nights_apart_and_reaches_its_standings() -> None:
    two_nights_of_a_season()
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        screen = app.screen
        names = painted(screen.query_one("#nights", DataTable))
        assert "ht 3" in names and "ht 2" in names  # the end that tells them apart
        await pilot.press("down")  # the closed night
        await settle(pilot)
        season = screen.query_one("#season", DataTable)
        for _ in range(4):  # Tab brings each of the night's tables into view in turn
            if screen.focused is season:
                break
            await pilot.press("tab")
            await settle(pilot)
        assert screen.focused is season
        shown = painted(season)
        assert all(racer in shown for racer in ("ana", "bob", "cy")) and "10" in shown
        standings = painted(screen.query_one("#standings", DataTable))
        assert standings == "" or "points" in standings  # scrolled past, or still shown


async def test_a_dialog_taller_than_60x20_opens_at_its_title_with_its_field_focused() -> None:
    # Issue 42's walk: the import dialog opened scrolled past its title at 60x20 (Textual
    # centres a field it focuses before the dialog is laid out).
    app = create_app(start="garage")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        await pilot.press("i")
        await settle(pilot)
        dialog = app.screen
        assert "Import a model" in painted(dialog)
        assert dialog.focused is dialog.query_one("#path", Input)
        await pilot.press(*"abc")
        assert dialog.query_one("#path", Input).value == "abc"


def test_a_name_loses_its_middle_never_the_words_that_tell_two_boards_apart() -> None:
    cut = _shortened("beginner-oval (physical)", 18, keeps_tail=True)
    assert str(cut) == "beginn… (physical)"
    assert str(_shortened("beginner-oval", 10, keeps_tail=True)) == "beginner-…"
    # The column's floor leaves room for its tail.
    natural, room = [24, 30], 30
    columns = [Col("track", keep=2, shrink_to=8, collapses=False, keeps_tail=True), Col("x", 1)]
    widths = fit_widths(natural, columns, room, 1, least=[14, 0])
    assert widths[0] is not None and widths[0] >= 14


async def test_an_export_of_one_board_has_the_track_column_the_table_shows(
    tmp_path: Path,
) -> None:
    """Point 9: the dialog says "the table as shown"; with one board the table shows its
    track, and so does the file."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ada", [11.0]))
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen) and "track" in screen.titles
        await pilot.press("x")
        app.screen.query_one("#answer", Input).value = str(tmp_path / "board.csv")
        await pilot.press("enter")
        await settle(pilot)
    rows = list(csv.DictReader((tmp_path / "board.csv").open()))
    assert rows[0]["track"] == "beginner-oval"


def test_a_model_name_loses_its_middle_so_siblings_stay_apart() -> None:
    v2 = _shortened("reinvent-2018-centerline-v2", 11, middle=True)
    v3 = _shortened("reinvent-2018-centerline-v3", 11, middle=True)
    assert str(v2) == "reinv…ne-v2" and str(v3) == "reinv…ne-v3"


def test_the_demo_caption_never_cuts_a_figure_in_the_middle() -> None:
    """Point 8: the welcome screen's demo said `best 0:06.3…` at 80x24."""
    from racer_tui.app.widgets.demo_race import figures_line
    from sim.race.engine import race_ticks
    from sim.race.rules import RaceRules
    from sim.tracks.catalog import resolve_track

    tick = next(
        t
        for t in race_ticks(resolve_track("reinvent_base"), RaceRules(window_seconds=30.0))
        if t.laps
    )
    for width in (40, 36, 30, 19):
        line = figures_line(tick, width)
        assert len(line) <= width and re.search(r"best \d:\d\d\.\d\d\d\b", line)


def test_a_model_without_a_camera_is_not_called_convolutional() -> None:
    """Point 13: vector models were labelled DEEP_CONVOLUTIONAL_NETWORK_SHALLOW."""
    from sim.garage.overview import network_words

    shallow = "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW"
    vector = network_words({"neural_network": shallow, "sensor": ["VECTOR"]})
    assert vector == "dense, shallow (no camera)"
    camera = network_words({"neural_network": shallow, "sensor": ["FRONT_FACING_CAMERA"]})
    assert camera == shallow


@pytest.mark.parametrize("section", ["races", "league", "training"])
async def test_nothing_is_cut_at_60x20(section: str) -> None:
    """Legible at 60x20: no table scrolls sideways, nothing reaches past the edge."""
    from tests.racer_tui.test_fits_80x24 import a_busy_league, cut_off

    a_busy_league()
    app = create_app(start=section)
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        assert cut_off(app) == []


async def test_the_nights_screen_fits_60x20() -> None:
    from tests.racer_tui.test_fits_80x24 import a_busy_league, cut_off

    a_busy_league()
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        await settle(pilot)
        await pilot.press("n")
        await settle(pilot)
        assert cut_off(app) == []

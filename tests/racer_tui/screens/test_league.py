"""The League section: leaderboard sorting, filters, row detail, export and the projector."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from textual.widgets import DataTable, Digits, Input, Select

from league.assembler import assemble
from league.opening import open_league
from league.races import record_race
from league.submissions import submit
from league.trust.replay import verify_races
from racer_tui.app.application import create_app
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.projector import ProjectorScreen
from racer_tui.app.widgets.entry_detail import EntryDetail
from sim.foundation.home import data_home
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.drivers import DriversByHash
from tests.league.helpers import model_folder, race_result
from tests.racer_tui.screens.tui_helpers import painted, settle, wait_for


def three_racers() -> None:
    """ada and bob on the oval (bob leads), cy alone on the hairpin."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ada", [12.0, 11.5, 11.8], model="ada-car"))
        record_race(league, race_result("bob", [11.0, 13.0, 12.5], offtracks=[0, 2, 0]))
        hairpin = resolve_track("hairpin-circuit")
        record_race(league, race_result("cy", [20.0], track=hairpin))


def racers(screen: LeagueScreen) -> list[str]:
    return [row.racer for row in screen.rows]


def headers(screen: LeagueScreen) -> list[str]:
    table = screen.query_one("#board", DataTable)
    return [str(column.label) for column in table.ordered_columns]


async def test_the_leaderboard_sorts_by_every_column_with_keys_and_clicks() -> None:
    three_racers()
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        # The league's order: track by track, best lap first.
        assert racers(screen) == ["bob", "ada", "cy"]
        assert headers(screen)[0] == "rank ▲"
        await pilot.press("s")  # the next column: racer
        assert racers(screen) == ["ada", "bob", "cy"]
        assert headers(screen)[1] == "racer ▲"
        await pilot.press("r")
        assert racers(screen) == ["cy", "bob", "ada"]
        assert headers(screen)[1] == "racer ▼"
        # Every column is reachable with s, and each sorts.
        titles = [title.split(" ")[0] for title in headers(screen)]
        for _ in titles:
            await pilot.press("s")
        # A click on a header sorts by it; a second click reverses.
        table = screen.query_one("#board", DataTable)
        columns = table.ordered_columns
        laps_index = [str(c.label).split(" ")[0] for c in columns].index("laps")
        x = sum(c.get_render_width(table) for c in columns[:laps_index]) + 1
        await pilot.click("#board", offset=(x, 0))
        await pilot.pause()
        assert racers(screen) == ["cy", "bob", "ada"]  # 1, 3, 3 valid laps (ties: rank order)
        await pilot.click("#board", offset=(x, 0))
        await pilot.pause()
        assert racers(screen) == ["bob", "ada", "cy"]
        assert "laps ▼" in headers(screen)


async def test_filters_and_the_ranking_method_change_the_rows() -> None:
    three_racers()
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        track = screen.query_one("#filter-track", Select)
        oval = resolve_track("beginner-oval").content_hash
        track.value = oval
        await settle(pilot)
        assert racers(screen) == ["bob", "ada"]
        assert "track" not in headers(screen)  # one track: no track column
        screen.query_one("#filter-by", Select).value = "average"
        await settle(pilot)
        # Averages of three laps: ada 11.77; bob's second lap carries two 3 s penalties.
        assert racers(screen) == ["ada", "bob"]
        assert any(title.startswith("best average") for title in headers(screen))


async def test_export_writes_the_table_as_shown(tmp_path: Path) -> None:
    three_racers()
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("s")  # racer order
        for name, check in (
            ("board.csv", "csv"),
            ("board.json", "json"),
            ("board.md", "markdown"),
            ("board.txt", "refused"),
        ):
            await pilot.press("x")
            dialog_input = app.screen.query_one("#answer", Input)
            # Proposed in the racer-tui folder, never the one the app started in (the host
            # walk: a host who started it in a clone would write into the repository).
            assert dialog_input.value == str(data_home() / "leaderboard.csv")
            dialog_input.value = str(tmp_path / name)
            await pilot.press("enter")
            await settle(pilot)
            if check == "refused":
                assert "End the file name with .csv" in painted(app.screen.query_one("#problem"))
                await pilot.press("escape")
                assert not (tmp_path / name).exists()
    rows = list(csv.DictReader((tmp_path / "board.csv").open()))
    assert [row["racer"] for row in rows] == ["ada", "bob", "cy"]
    assert rows[1]["best lap"] == "11.000" and rows[1]["track"] == "beginner-oval"
    document = json.loads((tmp_path / "board.json").read_text())
    assert [entry["racer"] for entry in document] == ["ada", "bob", "cy"]
    markdown = (tmp_path / "board.md").read_text()
    assert markdown.startswith("| rank | racer | model | track |")


async def test_a_submission_row_summarises_its_five_files(tmp_path: Path) -> None:
    folder = model_folder(tmp_path, "dee-car", laps=(12.5, 12.1, 12.9))
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        submit(league, assemble(str(folder), "dee"))
        record_race(league, race_result("ada", [12.0, 11.5]))
    app = create_app(start="league")
    async with app.run_test(size=(160, 40)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        assert racers(screen) == ["ada", "dee"]
        detail = screen.query_one(EntryDetail)
        assert "lap  1" in painted(detail) and "11.500 s" in painted(detail)
        await pilot.press("down")
        await settle(pilot)
        text = painted(detail)
        for expected in (
            "Model metadata",
            "action space: discrete",
            "Hyperparameters",
            "batch_size 64",
            "Training",
            "episodes: 20",
            "Evaluation",
            "trials: 3, 3 laps completed",
            "12.100 s",
        ):
            assert expected in text, expected


async def test_a_markup_looking_racer_name_is_shown_literally() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    name = "[bold red]Eve[/] **x**"
    with open_league() as league:
        record_race(league, race_result(name, [12.0]))
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        assert name in painted(app.screen.query_one("#board"))
        await pilot.press("p")
        await settle(pilot)
        assert isinstance(app.screen, ProjectorScreen)
        assert name in painted(app.screen.query_one("#projector-rows"))


async def test_the_board_shows_results_recorded_elsewhere_without_a_key() -> None:
    """A result recorded by another process (the command line, a sync) lands on the board
    shown within its poll, with the highlighted row kept."""
    three_racers()
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        await pilot.press("down")  # ada
        await settle(pilot)
        assert screen.highlighted is not None and screen.highlighted.racer == "ada"
        with open_league() as league:
            record_race(league, race_result("fay", [10.5]))
        await wait_for(pilot, lambda: "fay" in racers(screen))
        assert racers(screen) == ["fay", "bob", "ada", "cy"]
        assert screen.highlighted is not None and screen.highlighted.racer == "ada"


async def test_the_projector_shows_the_leader_and_picks_up_new_results() -> None:
    three_racers()
    app = create_app(start="league")
    async with app.run_test(size=(120, 40)) as pilot:
        await settle(pilot)
        await pilot.press("p")
        await settle(pilot)
        projector = app.screen
        assert isinstance(projector, ProjectorScreen)
        assert projector.query_one("#projector-leader", Digits).value == "0:11.000"
        assert "Leader: bob" in painted(projector.query_one("#projector-leader-name"))
        with open_league() as league:
            record_race(league, race_result("fay", [10.5]))
        projector.action_refresh_now()  # what the poll timer does every few seconds
        await settle(pilot)
        assert projector.query_one("#projector-leader", Digits).value == "0:10.500"
        assert "fay" in painted(projector.query_one("#projector-rows"))
        await pilot.press("escape")  # a kiosk: Esc does nothing
        assert app.screen is projector
        await pilot.press("q", "y")  # leaving asks first, then goes back
        assert isinstance(app.screen, LeagueScreen)


async def test_each_row_says_whether_it_was_replayed_here_is_verifiable_or_not() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    oval = resolve_track("beginner-oval")
    with open_league() as league:
        # The reference driver is on every machine: its race can be re-run here.
        reference = run_race(oval, RaceRules(window_seconds=30.0), racer="ada", keep_trace=False)
        record_race(league, reference)
        # A car nobody here has: nothing can re-run bob's race.
        record_race(league, race_result("bob", [13.0, 12.5], model="bobs-car"))
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        assert "verification" in headers(screen)
        standing = {row.racer: row.verification for row in screen.rows}
        assert standing == {"ada": "verifiable", "bob": "unverifiable"}
        await wait_for(pilot, lambda: "verifiable: its model is here" in painted(detail(screen)))
    with open_league() as league:
        verify_races(league, DriversByHash())  # `racer-tui sync verify`
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        screen = app.screen
        assert isinstance(screen, LeagueScreen)
        assert {row.racer: row.verification for row in screen.rows}["ada"] == "replayed"
        await wait_for(pilot, lambda: "replayed here" in painted(detail(screen)))


def detail(screen: LeagueScreen) -> EntryDetail:
    return screen.query_one(EntryDetail)

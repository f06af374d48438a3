"""The head-to-head board on the League screen: t reaches it after the lap boards, its
table and detail come from the league's records, the filters that do not apply say why,
export writes it as the command line does, and races recorded elsewhere land on it."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import pytest
from rich.text import Text
from textual.pilot import Pilot
from textual.widgets import DataTable, Input, Select

from league.head_to_head_board import read_head_to_head_board, rival_records
from league.head_to_heads import record_head_to_head
from league.nights import new_night
from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.widgets.entry_detail import EntryDetail
from racer_tui.app.widgets.footer import screen_keys
from sim.foundation.home import data_home
from sim.race.head_to_head import HeadToHeadResult
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, head_to_head_in_order, race_result
from tests.league.sync.leagues import head_to_head
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for
from tests.racer_tui.test_fits_80x24 import LONG_MODEL, LONG_RACER, cut_off
from tests.racer_tui.test_head_to_head_cli import run_cli

HAIRPIN = "hairpin-circuit"


@pytest.fixture(scope="module")
def three_cars() -> HeadToHeadResult:
    """A real race of three reference cars on the oval: its cars' laps make the others."""
    return head_to_head("x", "y", "z", seed=1)


def record(three_cars: HeadToHeadResult, *racers: str, **options: Any) -> None:
    with open_league() as league:
        night_id = options.pop("night_id", None)
        race = head_to_head_in_order(three_cars, *racers, **options)
        record_head_to_head(league, race, night_id=night_id)


def league_of_both(three_cars: HeadToHeadResult) -> None:
    """A time trial on the oval and one on the hairpin; three head-to-head races on the
    oval: ana beats bob, bob beats ana, then ana, bob and cy in that order."""
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        record_race(league, race_result("ana", [10.0], model="ana-car"))
        record_race(league, race_result("dee", [20.0], track=resolve_track(HAIRPIN)))
    record(three_cars, "ana", "bob", models=("ana-v1", "bob-car"))
    record(three_cars, "bob", "ana", models=("bob-car", "ana-v2"))
    record(three_cars, "ana", "bob", "cy", models=("ana-v2", "bob-car", "cy-car"))


def the_board() -> list[tuple[int, str, int, int]]:
    """The head-to-head board as the league holds it."""
    with open_league() as league:
        board = read_head_to_head_board(league)
    return [(row.rank, row.racer, row.wins, row.losses) for row in board.rows]


def shown(screen: LeagueScreen) -> list[tuple[int, str, int, int]]:
    assert screen.head_to_head is not None
    return [(row.rank, row.racer, row.wins, row.losses) for row in screen.head_to_head.rows]


def headers(screen: LeagueScreen) -> list[str]:
    return [str(column.label) for column in screen.query_one("#board", DataTable).ordered_columns]


def line(screen: LeagueScreen) -> str:
    return painted(screen.query_one("#board-race-type")).strip()


def detail(screen: LeagueScreen) -> str:
    """The row detail's text, all of it (it scrolls below the table)."""
    content = screen.query_one(EntryDetail).content
    assert isinstance(content, Text)
    return content.plain


def keys(screen: LeagueScreen) -> dict[str, bool]:
    """The footer's keys: description -> enabled (a disabled key is drawn dim)."""
    shown_keys, _ = screen_keys(screen)
    return {key.description: key.enabled for key in shown_keys}


async def league_screen(pilot: Pilot[Any]) -> LeagueScreen:
    await settle(pilot)
    screen = pilot.app.screen
    assert isinstance(screen, LeagueScreen)
    return screen


async def test_t_reaches_the_head_to_head_board_and_back(three_cars: HeadToHeadResult) -> None:
    league_of_both(three_cars)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await league_screen(pilot)
        assert line(screen) == "Time trial boards  ·  t switches to head-to-head"
        assert screen.head_to_head is None

        await pilot.press("t")
        await settle(pilot)
        assert line(screen) == "Head-to-head, ranked by wins  ·  t switches to time trial"
        assert shown(screen) == the_board() == [(1, "ana", 2, 1), (2, "bob", 1, 2), (3, "cy", 0, 1)]
        assert headers(screen) == [
            "rank",
            "racer",
            "car",
            "wins",
            "losses",
            "ahead of",
            "behind",
            "replayed",
        ]
        table = painted(screen.query_one("#board"))
        assert "ana-v2 (+1)" in table and "0 of 3" in table
        assert keys(screen)["Race type"]

        # The highlighted racer's record against each rival, and their races.
        text = detail(screen)
        assert "ana  1st of 3" in text
        assert "2 wins, 1 loss in 3 starts" in text
        await pilot.press("down")
        await settle(pilot)
        text = detail(screen)
        assert text.startswith("bob  2nd of 3")
        assert painted(screen.query_one(EntryDetail)).startswith(" bob  2nd of 3")
        with open_league() as league:
            records = rival_records(read_head_to_head_board(league), "bob")
        assert [(r.rival, r.wins, r.losses) for r in records] == [("ana", 1, 2), ("cy", 1, 0)]
        assert "ana  1 win, 2 losses" in text and "cy   1 win, 0 losses" in text
        assert "Races (3, newest first)" in text
        assert "2nd of 3 (bob-car) · ahead of cy · behind ana" in text
        assert "verifiable: every car's model is here, not raced again yet" in text

        await pilot.press("t")
        await settle(pilot)
        assert line(screen) == "Time trial boards  ·  t switches to head-to-head"
        assert screen.head_to_head is None
        assert [row.racer for row in screen.rows] == ["ana", "dee"]


async def test_filters_and_keys_that_do_not_apply_say_why(three_cars: HeadToHeadResult) -> None:
    league_of_both(three_cars)
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        night = new_night(league, resolve_track(TRACK), name="friday")
    record(three_cars, "cy", "ana", night_id=night.id)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        screen = await league_screen(pilot)
        season = screen.query_one("#filter-season", Select)
        by = screen.query_one("#filter-by", Select)
        by.value = "average"
        await settle(pilot)

        await pilot.press("t")
        await settle(pilot)
        assert season.disabled and by.disabled
        assert season.tooltip == "Head-to-head races are not on nights' seasons yet."
        assert by.tooltip == "A head-to-head board ranks by wins, not by laps."
        filters = painted(screen.query_one("#board-filters"))
        assert "no seasons" in filters and "by wins" in filters
        assert "average" not in filters
        # s, r and a header click say why the board does not sort, and the order stays.
        before = shown(screen)
        await pilot.press("s")
        await pilot.press("r")
        await pilot.click("#board", offset=(8, 0))  # the racer header
        await settle(pilot)
        assert shown(screen) == before
        assert headers(screen)[:2] == ["rank", "racer"]  # no sort arrow
        said = "A head-to-head board is ranked by wins: s and r sort the lap boards."
        assert notes.text().count(said) == 3

        # The track and the night apply: the night's race alone.
        screen.query_one("#filter-night", Select).value = night.id
        await settle(pilot)
        assert shown(screen) == [(1, "cy", 1, 0), (2, "ana", 0, 1)]
        # The hairpin has no head-to-head race: its time trials, and the oval brings the
        # head-to-head board back (the host's choice).
        screen.query_one("#filter-night", Select).clear()
        track = screen.query_one("#filter-track", Select)
        track.value = resolve_track(HAIRPIN).content_hash
        await settle(pilot)
        assert screen.head_to_head is None and [row.racer for row in screen.rows] == ["dee"]
        assert not season.disabled and not by.disabled
        assert by.value == "average" and season.tooltip is None  # as the host left them
        track.value = resolve_track(TRACK).content_hash
        await settle(pilot)
        assert shown(screen) == the_board()  # the night's race counts on its track's board
        assert [racer for _, racer, _, _ in shown(screen)] == ["ana", "cy", "bob"]


async def test_export_writes_the_board_as_the_command_line_does(
    three_cars: HeadToHeadResult, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    league_of_both(three_cars)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        await league_screen(pilot)
        await pilot.press("t")
        await settle(pilot)
        for name in ("board.csv", "board.json", "board.md"):
            await pilot.press("x")
            await settle(pilot)
            answer = app.screen.query_one("#answer", Input)
            assert answer.value == str(data_home() / "head-to-head.csv")
            answer.value = str(tmp_path / name)
            await pilot.press("enter")
            await settle(pilot)
    rows = list(csv.DictReader((tmp_path / "board.csv").open()))
    assert [(row["rank"], row["racer"], row["wins"], row["losses"]) for row in rows] == [
        (str(rank), racer, str(wins), str(losses)) for rank, racer, wins, losses in the_board()
    ]
    assert rows[0]["car"] == "ana-v2 (+1)" and rows[0]["replayed"] == "0 of 3"
    assert rows[0]["ahead of"] == "3" and rows[0]["behind"] == "1"
    code, out, err = run_cli(
        capsys, "leaderboard", "--race-type", "head-to-head", "--format", "json"
    )
    assert code == 0, err
    assert json.loads((tmp_path / "board.json").read_text()) == json.loads(out)
    markdown = (tmp_path / "board.md").read_text().splitlines()
    assert markdown[0] == "| rank | racer | car | wins | losses | ahead of | behind | replayed |"


async def test_a_race_recorded_elsewhere_lands_and_a_restart_shows_the_same(
    three_cars: HeadToHeadResult,
) -> None:
    league_of_both(three_cars)
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await league_screen(pilot)
        await pilot.press("t")
        await settle(pilot)
        await pilot.press("down")  # bob
        await settle(pilot)
        # Another process (the command line, a sync) records a race: no key is pressed.
        record(three_cars, "cy", "ana", "bob")
        await wait_for(pilot, lambda: ("cy", 1) in [(r, w) for _, r, w, _ in shown(screen)])
        assert shown(screen) == the_board()
        highlighted = screen.highlighted_racer
        assert highlighted is not None and highlighted.racer == "bob"  # the cursor kept
        assert "Races (4, newest first)" in detail(screen)
        before = shown(screen)
    again = create_app(start="league")
    async with again.run_test(size=(80, 24)) as pilot:
        screen = await league_screen(pilot)
        await pilot.press("t")
        await settle(pilot)
        assert shown(screen) == before  # from the league, not the last app's memory


async def test_a_league_of_head_to_heads_alone(three_cars: HeadToHeadResult) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    record(three_cars, "ana", "bob")
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        screen = await league_screen(pilot)
        assert shown(screen) == [(1, "ana", 1, 0), (2, "bob", 0, 1)]
        assert line(screen) == "Head-to-head, ranked by wins  (no other race type has laps here)"
        assert "Race type" not in keys(screen)
        await pilot.press("p")
        await pilot.press("v")
        await settle(pilot)
        assert app.screen is screen  # no projector of a lap board nobody asked for
        assert "The projector shows lap boards, not the head-to-head board yet." in notes.text()
        assert "A recorded head-to-head race is not replayed in the app yet" in notes.text()


async def test_at_60x20_long_names_still_read_apart(three_cars: HeadToHeadResult) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    record(three_cars, "Alexandra Montgomery", "Alexandra Montgolfier", "bob")
    app = create_app(start="league")
    async with app.run_test(size=(60, 20)) as pilot:
        screen = await league_screen(pilot)
        assert headers(screen)[:5] == ["rank", "racer", "wins", "losses", "ahead of"]
        rows = painted(screen.query_one("#board")).splitlines()[1:4]
        names = [row[6:].split("  ")[0].strip() for row in rows]
        assert len(set(names)) == 3
        assert names[0].startswith("Alexandra Montgom") and names[1].startswith("Alexandra Montgol")


@pytest.mark.parametrize("size", [(80, 24), (60, 20)], ids=["80x24", "60x20"])
async def test_nothing_is_cut_with_the_long_names_real_leagues_have(
    three_cars: HeadToHeadResult, size: tuple[int, int]
) -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    record(three_cars, LONG_RACER, "bob", "Chidimma Okonkwo-Adeyemi", models=(LONG_MODEL,) * 3)
    app = create_app(start="league")
    async with app.run_test(size=size) as pilot:
        screen = await league_screen(pilot)
        assert screen.head_to_head is not None
        assert cut_off(app) == []

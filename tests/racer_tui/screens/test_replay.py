"""Replaying races recorded in the league: from the Races section's list and from a
leaderboard entry, with one sentence when a race cannot be replayed here."""

from __future__ import annotations

from dataclasses import replace

from textual.widgets import DataTable, Select

from league.opening import open_league
from league.races import record_race
from racer_tui.app.application import create_app
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.widgets.model_detail import seconds_text
from racer_tui.text.clocks import clock_text
from sim.race.engine import run_race
from sim.race.result import RaceResult
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for

SHORT = RaceRules(window_seconds=25.0)


def recorded_reference_race(racer: str = "ada") -> RaceResult:
    """What `racer-tui --race reference --track beginner-oval --record` stores: the
    reference driver's race with its trace, recorded into the league."""
    result = run_race(resolve_track("beginner-oval"), SHORT, racer=racer, keep_trace=True)
    with open_league() as league:
        record_race(league, result)
    return result


def lap_times(race: RaceScreen) -> list[str]:
    table = race.query_one("#laps", DataTable)
    return [str(table.get_row_at(i)[1]) for i in range(table.row_count)]


async def test_a_recorded_race_replays_from_the_races_section() -> None:
    result = recorded_reference_race()
    best = result.best_lap
    assert len(result.laps) >= 2
    with open_league() as league:  # an older race without its trace, listed under it
        record_race(league, race_result("bob", [30.0], started_at="2024-01-01T10:00:00.000Z"))
    app = create_app(start="races")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        assert [race.racer for race in races.recorded] == ["ada", "bob"]
        shown = painted(races.query_one("#recorded-races"))
        assert "ada" in shown and "beginner-oval" in shown and "reference" in shown
        assert best is not None and seconds_text(best.time_seconds) in shown

        await pilot.press("p")  # no race this session: p replays the league's highlighted race
        await settle(pilot)
        replay = app.screen
        assert isinstance(replay, RaceScreen)
        assert replay.setup.replay is not None
        assert replay.setup.replay.result_id == result.result_id
        await pilot.press("e")  # to the end of the recorded race
        await wait_for(pilot, lambda: len(lap_times(replay)) == len(result.laps))
        assert lap_times(replay) == [clock_text(lap.time_seconds) for lap in result.laps]
        await pilot.press("escape")
        assert app.screen is races


async def test_a_race_without_a_trace_or_track_here_says_so_in_one_sentence() -> None:
    traced = run_race(resolve_track("beginner-oval"), SHORT, racer="cy", keep_trace=True)
    with open_league() as league:
        record_race(league, race_result("bob", [30.0], started_at="2024-01-01T10:00:00.000Z"))
        record_race(league, replace(traced, track_name="moon-base", track_hash="f" * 64))
    app = create_app(start="races")
    async with app.run_test(size=(120, 36)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        races.query_one("#recorded-races", DataTable).focus()
        await pilot.press("enter")  # the newest: on a track this machine does not have
        await settle(pilot)
        assert app.screen is races
        assert "'moon-base', which is not on this machine" in notes.text("error")
        # The app offers its own way to get the track, not a shell command.
        assert "on the Tracks screen (i there)" in notes.text("error")
        assert "racer-tui" not in notes.text("error")
        await pilot.press("down", "enter")
        await settle(pilot)
        assert app.screen is races
        assert "has no trace here" in notes.text("error")
        assert "Traceback" not in notes.text()


async def test_a_leaderboard_race_entry_replays_with_v() -> None:
    result = recorded_reference_race("ada")
    app = create_app(start="league")
    async with app.run_test(size=(120, 36)) as pilot:
        notes = Notifications(app)
        await settle(pilot)
        board = app.screen
        assert isinstance(board, LeagueScreen)
        assert "v replays this race" in painted(board.query_one("#entry-detail"))
        await pilot.press("v")
        await settle(pilot)
        replay = app.screen
        assert isinstance(replay, RaceScreen)
        assert replay.setup.replay is not None
        assert replay.setup.replay.result_id == result.result_id
        assert not notes.messages


async def test_the_first_race_of_a_track_races_the_leagues_best_lap_as_its_ghost() -> None:
    best = recorded_reference_race("bob")  # the league has a lap on this track
    app = create_app(start="races")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        races.query_one("#race-track", Select).value = "beginner-oval"
        await pilot.pause()
        await pilot.press("s")  # no race this session yet
        race = app.screen
        assert isinstance(race, RaceScreen)
        assert race.setup.ghost is not None
        assert best.best_lap is not None
        assert race.setup.ghost.lap_seconds == best.best_lap.time_seconds
        assert race.setup.leader_seconds == best.score
        await pilot.press("escape")
        await settle(pilot)

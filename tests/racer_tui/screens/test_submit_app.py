"""Submitting to the league from the app: a race of the Races section (u), and a garage
model's latest evaluation (u, as `racer-tui submit` does); the racer is asked once."""

from __future__ import annotations

import json

from textual.widgets import DataTable, Input, Select

from league.opening import open_league
from league.races import race_replay, recent_races
from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import ConfirmDialog, InputDialog
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.widgets.footer import RacerFooter
from sim.training.evaluation import evaluate_model
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, trained_model

MARKUP_NAME = "Ada [bold]L[/bold]"  # racer names are plain text, shown literally


async def test_a_models_race_is_submitted_once_under_the_racers_name() -> None:
    trained_model("ada-car", track="beginner-oval")
    app = create_app(start="races")
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        await pilot.press("u")
        assert "no race to submit yet" in notes.text("warning")

        # The reference driver's race is not a league entry.
        races.query_one("#race-window", Select).value = 60.0
        await pilot.press("s")
        await settle(pilot)
        await pilot.press("escape")
        await pilot.press("u")
        assert "reference driver's races are not league entries" in notes.text("warning")

        await pilot.press("down", "s")  # ada-car, on her own track
        race = app.screen
        assert isinstance(race, RaceScreen)
        await settle(pilot)
        await pilot.press("escape")
        assert race.result is not None
        table = races.query_one("#race-results", DataTable)
        labels = [table.get_row_at(row)[1].plain for row in range(table.row_count)]
        table.move_cursor(row=labels.index("ada-car"))

        await pilot.press("u")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, InputDialog)
        # An empty league: nobody is offered (never the machine's user name, "root").
        assert dialog.query_one(Input).value == ""
        await pilot.press("ctrl+a", "ctrl+k", *MARKUP_NAME, "enter")
        await settle(pilot)
        assert app.screen is races
        assert f"{MARKUP_NAME} is 1st of 1 on beginner-oval's leaderboard" in notes.text()
        row = table.get_row_at(table.cursor_row)
        assert row[1].plain == "✓ ada-car"  # marked as submitted

        # Asked once: a second press does not ask again, and does not submit twice.
        await pilot.press("u")
        await settle(pilot)
        assert app.screen is races
        assert "already in the league" in notes.text("warning")
        recorded = races.query_one("#recorded-races", DataTable)
        assert recorded.row_count == 1
        assert recorded.get_row_at(0)[1].plain == MARKUP_NAME

    with open_league() as league:
        (stored,) = recent_races(league)
        assert (stored.racer, stored.model_name) == (MARKUP_NAME, "ada-car")
        assert stored.has_trace
        replay = race_replay(league, stored.race_id)  # it replays from its trace
        assert replay.result.result_id == race.result.result_id


async def test_the_garage_submits_the_latest_evaluation() -> None:
    folder = trained_model("eva", track="beginner-oval")
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        garage = app.screen
        assert isinstance(garage, GarageScreen)
        await pilot.press("u")
        assert "eva has no evaluation to submit yet; press v to evaluate it first." in notes.text(
            "warning"
        )
        evaluate_model(folder, trials=1)
        await pilot.press("u")
        await settle(pilot)
        assert isinstance(app.screen, InputDialog)
        await pilot.press("ctrl+a", "ctrl+k", *"Eve", "enter")
        await settle(pilot)
        assert "Submitted eva for Eve on beginner-oval" in notes.text()
        assert "Eve is 1st of 1 on beginner-oval's leaderboard." in notes.text()
        await pilot.press("u")  # the racer is offered again; the same evaluation not re-added
        await settle(pilot)
        assert isinstance(app.screen, InputDialog)
        assert app.screen.query_one(Input).value == "Eve"
        await pilot.press("enter")
        await settle(pilot)
        assert "already in the league for Eve" in notes.text()

        # The Races section offers Eve too; a host could type another racer's name there.
        await pilot.press("3")
        await settle(pilot)
        races = app.screen
        assert isinstance(races, RacesScreen)
        races.query_one("#race-window", Select).value = 60.0
        await pilot.press("down", "s")
        await settle(pilot)
        await pilot.press("escape", "u")
        await settle(pilot)
        assert isinstance(app.screen, InputDialog)
        assert app.screen.query_one(Input).value == "Eve"
        await pilot.press("enter")
        await settle(pilot)
        assert "Submitted Eve's race with eva on beginner-oval" in notes.text()
    with open_league() as league:
        assert league.conn.execute("SELECT count(*) FROM submissions").fetchone()[0] == 1
        assert [race.racer for race in recent_races(league)] == ["Eve"]


async def test_a_racer_name_that_cannot_be_one_is_explained_in_the_dialog() -> None:
    folder = trained_model("eva", track="beginner-oval")
    evaluate_model(folder, trials=1)
    app = create_app(start="garage")
    async with app.run_test(size=(120, 36)) as pilot:
        await settle(pilot)
        await pilot.press("u")
        await settle(pilot)
        dialog = app.screen
        assert isinstance(dialog, InputDialog)
        dialog.query_one(Input).value = "x" * 101
        await pilot.press("enter")
        assert app.screen is dialog
        problem = str(dialog.query_one("#problem").render())
        assert "cannot be a racer name" in problem
        await pilot.press("escape")
        await settle(pilot)
    with open_league() as league:
        assert league.conn.execute("SELECT count(*) FROM submissions").fetchone()[0] == 0


async def test_submitting_is_in_the_palette_and_both_footers() -> None:
    app = create_app(start="races")
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        texts = [command.text for command in app.palette_commands(app.screen)]
        assert "Races: Submit to league" in texts
        assert "Garage: Submit" in texts
        assert "u Submit to league" in painted(app.screen.query_one(RacerFooter))
        await pilot.press("1")
        await settle(pilot)
        assert "u Submit" in painted(app.screen.query_one(RacerFooter))  # at 80 columns too


async def test_an_evaluation_older_than_the_last_training_asks_first() -> None:
    folder = trained_model("eva", track="beginner-oval")
    evaluate_model(folder, trials=1)
    # The trainer's last word, dated after the evaluation: it trained again since.
    state = {"state": "finished", "updated_at": "2999-01-01T00:00:00+00:00"}
    folder.training_state_file.write_text(json.dumps(state), encoding="utf-8")
    app = create_app(start="garage")
    notes = Notifications(app)
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        await pilot.press("u")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmDialog)
        await pilot.press("n")  # not now: nothing is submitted
        await settle(pilot)
        await pilot.press("u")
        await settle(pilot)
        await pilot.press("y")
        await settle(pilot)
        assert isinstance(app.screen, InputDialog)
        await pilot.press(*"Eve", "enter")
        await settle(pilot)
        assert "Submitted eva for Eve" in notes.text()
    with open_league() as league:
        assert league.conn.execute("SELECT count(*) FROM submissions").fetchone()[0] == 1

"""The new user's whole evening, as the README tells it, in one Pilot test.

Empty data folder -> the welcome screen's demo race -> create a model (n) -> train it (t)
with a real training child and watch the charts fill -> evaluate it (e, one trial) -> race
it (3, s) in the live race view -> submit the race (u) -> see it on the leaderboard (5)
-> export the leaderboard as CSV (x). Waits for events and workers, never for time.
"""

from __future__ import annotations

import contextlib
import csv
import os
import signal
from pathlib import Path
from typing import Any

import pytest
from textual.app import App
from textual.screen import Screen
from textual.widgets import Input, Select

from racer_tui.app.application import create_app
from racer_tui.app.screens.dialogs import InputDialog
from racer_tui.app.screens.evaluation import EvaluationScreen
from racer_tui.app.screens.garage import GarageScreen
from racer_tui.app.screens.league import LeagueScreen
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.race_screen import RaceScreen
from racer_tui.app.screens.races import RacesScreen
from racer_tui.app.screens.train_dialog import TrainDialog
from racer_tui.app.screens.training import TrainingScreen
from racer_tui.app.screens.welcome import WelcomeScreen
from racer_tui.app.widgets.chart import LineChart
from racer_tui.app.widgets.demo_race import DemoRace
from racer_tui.app.widgets.training_charts import TrainingCharts
from sim.garage.folder import open_model
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, wait_for

pytestmark = pytest.mark.slow

MODEL = "first-car"
RACER = "Ada [red]L[/red]"  # a racer's name is plain text: shown literally, never as markup
# The smallest training the child supports: few cars, tiny PPO batches, no periodic
# evaluation or checkpoint; the budget below is a few seconds of training after start-up.
TINY_TRAINING = (
    "--cars", "8",
    "--min-samples", "64",
    "--max-samples", "256",
    "--evaluation-seconds", "0",
    "--checkpoint-seconds", "0",
    "--seed", "5",
)  # fmt: skip
BUDGET_MINUTES = "1"  # the least the dialog takes; the racer stops it after the first charts
RACE_WINDOW = 60.0  # the league's is 4:00; the flow is the same, only the clock is longer


def current_screen(app: App[Any]) -> Screen[Any]:
    """The screen on top now (a call, so a type checker does not carry an earlier
    isinstance check of `app.screen` across key presses)."""
    return app.screen


async def test_a_new_user_goes_from_the_demo_race_to_the_leaderboard(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(TrainingScreen, "worker_options", TINY_TRAINING)
    app = create_app()
    notes = Notifications(app)
    training: TrainingScreen | None = None
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            # First run: the welcome screen, with the reference driver lapping.
            await pilot.pause()
            assert isinstance(app.screen, WelcomeScreen)
            demo = app.screen.query_one(DemoRace)
            await wait_for(pilot, lambda: demo.car is not None, tries=300)
            first_position = demo.car
            await wait_for(pilot, lambda: demo.car != first_position, tries=300)

            # Create a model from there; it lands in the garage.
            await pilot.press("n")
            assert isinstance(app.screen, ModelEditorScreen)
            await pilot.press(*MODEL, "ctrl+s")
            await settle(pilot)
            garage = app.screen
            assert isinstance(garage, GarageScreen)
            assert garage.highlighted_name == MODEL

            # Train it: t asks for the time budget, then the child trains and the charts fill.
            await pilot.press("t")
            await settle(pilot)
            assert isinstance(app.screen, TrainDialog)
            await pilot.press("ctrl+a", "ctrl+k", *BUDGET_MINUTES, "enter")
            on_top = current_screen(app)
            assert isinstance(on_top, TrainingScreen)
            training = on_top
            await wait_for(pilot, lambda: training.live is not None and training.live.pid > 0)
            figures = training.figures
            await wait_for(
                pilot, lambda: MODEL in figures and len(figures[MODEL].rewards) >= 1, tries=1200
            )
            charts = training.query_one(TrainingCharts)
            charts.redraw_now()
            assert charts.query_one("#chart-reward", LineChart).values
            await pilot.press("s")  # enough for a first try: stop (a checkpoint is kept)
            await wait_for(pilot, lambda: training.live is None, tries=1200)
            ended = figures[MODEL].ended
            assert ended is not None and ended.kind == "stopped", ended
            assert open_model(MODEL).has_policy()

            # Evaluate it: one trial.
            await settle(pilot)
            await pilot.press("e")
            evaluation = app.screen
            assert isinstance(evaluation, EvaluationScreen)
            await pilot.press("ctrl+a", "ctrl+k", "1", "enter")
            await settle(pilot)
            assert evaluation.report is not None and len(evaluation.report.trials) == 1
            await pilot.press("escape")

            # Race it in the Races section, live.
            await pilot.press("3")
            await settle(pilot)
            races = app.screen
            assert isinstance(races, RacesScreen)
            assert [driver.label for driver in races.drivers] == ["reference driver", MODEL]
            races.query_one("#race-window", Select).value = RACE_WINDOW
            await pilot.press("down", "s")  # the model, on its own track
            race = app.screen
            assert isinstance(race, RaceScreen)
            assert race.setup.rules.window_seconds == RACE_WINDOW
            await wait_for(pilot, lambda: race.frames >= 2, tries=300)  # drawn as it happens
            await settle(pilot)  # the simulation has finished
            await pilot.press("e")  # skip the playback to the end
            assert "Finished" in painted(race.query_one("#race-facts"))
            await pilot.press("escape")
            assert current_screen(app) is races and race.result is not None

            # Submit it: the racer's name is asked once, then the place is told.
            await pilot.press("u")
            await settle(pilot)
            assert isinstance(app.screen, InputDialog)
            await pilot.press("ctrl+a", "ctrl+k", *RACER, "enter")
            await settle(pilot)
            track = race.setup.track.name
            assert f"{RACER} is 1st of 1 on {track}'s leaderboard." in notes.text()

            # The League section shows it.
            await pilot.press("5")
            await settle(pilot)
            league = app.screen
            assert isinstance(league, LeagueScreen)
            assert [(row.display_name, row.model) for row in league.rows] == [(RACER, MODEL)]
            assert RACER in painted(league.query_one("#board"))

            # And exports it.
            await pilot.press("x")
            dialog = app.screen
            assert isinstance(dialog, InputDialog)
            exported = tmp_path / "board.csv"
            dialog.query_one(Input).value = str(exported)
            await pilot.press("enter")
            await settle(pilot)
            assert not notes.text("error"), notes.text("error")
    finally:  # a failed test must not leave a training child behind
        if training is not None and training.live is not None and training.live.pid > 0:
            with contextlib.suppress(ProcessLookupError):
                os.kill(training.live.pid, signal.SIGKILL)
    with exported.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 1
    assert RACER in rows[0].values() and MODEL in rows[0].values()

"""Evaluating from the app: the trials count, the console-like table, the metrics file."""

from __future__ import annotations

from textual.widgets import DataTable, Input

from racer_tui.app import create_app
from racer_tui.screens.evaluation import EvaluationScreen, trials_problem
from sim.garage.folder import open_model
from tests.racer_tui.screens.tui_helpers import Notifications, settle, trained_model


def test_the_trials_count_is_checked() -> None:
    assert trials_problem("3") is None
    assert "between 1 and 100" in str(trials_problem("0"))
    assert "whole number" in str(trials_problem("many"))


async def test_evaluate_from_the_garage_fills_the_table_and_writes_metrics() -> None:
    trained_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        await pilot.press("v")
        screen = app.screen
        assert isinstance(screen, EvaluationScreen)
        screen.query_one("#trials", Input).value = "2"
        await pilot.press("enter")
        await settle(pilot)
        table = screen.query_one("#evaluation-results", DataTable)
        assert table.row_count == 2
        trial, _time, completed, status = (cell.plain for cell in table.get_row_at(0))
        assert trial == "1" and completed.endswith("%") and status
        assert screen.report is not None
        assert screen.report.metrics_file is not None and screen.report.metrics_file.is_file()
    assert len(open_model("ada").evaluation_files()) == 1


async def test_an_untrained_model_is_not_evaluated() -> None:
    from sim.garage.options import new_model

    new_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        await settle(pilot)
        notes = Notifications(app)
        await pilot.press("v")
        assert not isinstance(app.screen, EvaluationScreen)
        assert "train it first" in notes.text("warning")

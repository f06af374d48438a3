"""Evaluating from the app: the trials count, the console-like table, the metrics file."""

from __future__ import annotations

from typing import Any

from textual.pilot import Pilot
from textual.widgets import DataTable, Input

from racer_tui.app.application import create_app
from racer_tui.app.jobs import Job, JobState
from racer_tui.app.screens.evaluation import EvaluationScreen, trials_problem
from racer_tui.app.widgets.job_line import JobLine
from sim.garage.folder import open_model
from tests.racer_tui.screens.tui_helpers import Notifications, painted, settle, trained_model


def test_the_trials_count_is_checked() -> None:
    assert trials_problem("3") is None
    assert "between 1 and 100" in str(trials_problem("0"))
    assert "whole number" in str(trials_problem("many"))


async def open_evaluation(pilot: Pilot[Any]) -> EvaluationScreen:
    """From the garage, with its first model highlighted."""
    await settle(pilot)
    await pilot.press("v")
    screen = pilot.app.screen
    assert isinstance(screen, EvaluationScreen)
    return screen


async def test_evaluate_from_the_garage_fills_the_table_and_writes_metrics() -> None:
    trained_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(100, 30)) as pilot:
        screen = await open_evaluation(pilot)
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


async def test_an_evaluation_shows_its_progress_then_how_it_ended() -> None:
    trained_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        screen = await open_evaluation(pilot)
        seen: list[Job] = []
        show = screen._show_job

        def record(job: Job) -> None:
            seen.append(job)
            show(job)

        screen._show_job = record  # type: ignore[method-assign]
        screen.query_one("#trials", Input).value = "2"
        await pilot.press("enter")
        await settle(pilot)
        assert seen[0].state is JobState.RUNNING and seen[0].what == "Running 2 trials of ada"
        running = [job.done for job in seen if job.state is JobState.RUNNING]
        assert len(running) >= 3 and running == sorted(running)  # it moved while it ran
        assert screen.job.state is JobState.DONE
        line = " ".join(painted(screen.query_one(JobLine)).split())
        assert "Done at" in line and "of 2 trials completed the lap" in line
        assert "%" not in line  # the bar goes once the job is over


async def test_an_evaluation_that_fails_says_why_and_what_to_do_on_the_screen() -> None:
    folder = trained_model("ada")
    app = create_app(start="garage")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        screen = await open_evaluation(pilot)
        folder.policy_file.write_bytes(b"not a policy")  # damaged after the garage looked
        screen.query_one("#trials", Input).value = "1"
        await pilot.press("enter")
        await settle(pilot)
        assert screen.job.state is JobState.FAILED
        line = " ".join(painted(screen.query_one(JobLine)).split())
        assert "Failed at" in line and "ctrl+e to try again" in line
        assert "Traceback" not in line
        assert "%" not in line  # no bar left spinning
        assert notes.text("error") == ""  # on the screen, not a passing notification

"""Evaluate a model from the app: DeepRacer-style time-trial trials, one lap each.

The racer picks the number of trials; the evaluation runs in a thread worker (it loads the
policy, which imports torch, and drives the trials: a second or two for vector and lidar
models, longer for camera ones) with a progress bar and its ETA, and fills a table like the
DeepRacer console's: trial, time, % track completed, status. The library writes DRfC's
evaluation files into the model folder, as the CLI does. The job's status (running, done,
failed with what to do) is one `Job`, drawn by a `JobLine`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.message import Message
from textual.widgets import Button, DataTable, Input, Label, Static
from textual.worker import Worker, WorkerState

from racer_tui.app.jobs import Job, JobState
from racer_tui.app.screens.base import RacerScreen, error_message
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.widgets.model_detail import seconds_text
from racer_tui.app.widgets.table_fill import FittedTable
from sim.foundation.plural import counted
from sim.garage.folder import open_model
from sim.training.evaluation import DEFAULT_TRIALS, MAX_TRIALS, EvaluationReport, evaluate_model

COLUMNS = ("trial", "time", "% completed", "status")
STATUS_STYLES = {"Lap complete": "green", "In progress": "dim", "Time Up": "yellow"}


def trials_problem(text: str) -> str | None:
    """None when `text` is a valid number of trials, else what to type instead."""
    try:
        trials = int(text)
    except ValueError:
        return f"Give the number of trials as a whole number from 1 to {MAX_TRIALS}."
    if not 1 <= trials <= MAX_TRIALS:
        return f"The number of trials must be between 1 and {MAX_TRIALS}."
    return None


def report_cells(report: EvaluationReport) -> list[tuple[Text, ...]]:
    """The console's table rows: trial, time, % track completed, status."""
    return [
        (
            Text(str(trial.trial)),
            Text(seconds_text(trial.seconds)),
            Text(f"{trial.progress:.1f} %"),
            Text(trial.status, style=STATUS_STYLES.get(trial.status, "red")),
        )
        for trial in report.trials
    ]


def summary_text(report: EvaluationReport) -> Text:
    text = Text()
    text.append(f"{report.laps} of {counted(len(report.trials), 'trial')} completed the lap on ")
    text.append(report.track)
    text.append(f" · mean progress {report.mean_progress:.1f} %")
    if report.best_lap is not None:
        text.append(f" · best lap {seconds_text(report.best_lap)}")
    if report.metrics_file is not None:
        text.append(f"\nSaved {report.metrics_file.name} in the model folder.", style="dim")
    return text


@dataclass
class EvaluationDone(Message):
    report: EvaluationReport


@dataclass
class EvaluationProgress(Message):
    fraction: float


class EvaluationScreen(RacerScreen[None]):
    """Trials count, an Evaluate button, and the results table."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "leave", "Back"),
        # Above the trials field's own ctrl+e (end of line): in a 3-digit field the racer
        # means Evaluate, and the footer shows it.
        Binding("ctrl+e", "evaluate", "Evaluate", tooltip="Run the trials", priority=True),
    ]
    DEFAULT_CSS = """
    EvaluationScreen { padding: 0 1; }
    EvaluationScreen #evaluation-title { text-style: bold; color: $accent; margin: 1 0; }
    EvaluationScreen #evaluation-form { height: auto; }
    EvaluationScreen #evaluation-form > Label { padding: 1 1 0 0; }
    EvaluationScreen #trials { width: 12; }
    EvaluationScreen #evaluation-summary { height: auto; margin: 1 0; }
    EvaluationScreen JobLine { margin: 0 0 1 0; }
    EvaluationScreen #evaluation-results { height: 1fr; }
    """

    def __init__(self, model: str, trials: int = DEFAULT_TRIALS) -> None:
        super().__init__()
        self.model = model
        self.trials = trials
        self.report: EvaluationReport | None = None
        self.job = Job()
        self._shown_percent = -1

    def compose(self) -> ComposeResult:
        yield Static(Text(f"Evaluate {self.model}"), id="evaluation-title")
        with Horizontal(id="evaluation-form"):
            yield Label("Trials")
            yield Input(str(self.trials), id="trials", type="integer")
            yield Button("Evaluate (ctrl+e)", id="run", variant="primary")
        yield Static(
            Text(
                "Each trial drives one lap from the start line with the trained policy, "
                "as a DeepRacer evaluation does."
            ),
            id="evaluation-summary",
        )
        yield JobLine(id="evaluation-job")
        yield FittedTable(id="evaluation-results", cursor_type="row", zebra_stripes=True)
        yield RacerFooter()

    def on_mount(self) -> None:
        self.query_one("#evaluation-results", DataTable).add_columns(*COLUMNS)
        self.query_one("#trials", Input).focus()

    def action_leave(self) -> None:
        self.dismiss(None)

    @property
    def running(self) -> bool:
        return self.job.state is JobState.RUNNING

    def _show_job(self, job: Job) -> None:
        self.job = job
        self.query_one(JobLine).show(job)

    @on(Input.Submitted, "#trials")
    @on(Button.Pressed, "#run")
    def action_evaluate(self) -> None:
        if self.running:
            self.notify("The evaluation is still running.", severity="warning")
            return
        text = self.query_one("#trials", Input).value.strip()
        problem = trials_problem(text)
        if problem is not None:
            self.notify(problem, severity="error", markup=False)
            return
        self.trials = int(text)
        what = f"Running {counted(self.trials, 'trial')} of {self.model}"
        self._shown_percent = -1
        self._show_job(self.job.running(what, total=100, now=time.monotonic(), wall=time.time()))
        self._evaluate(self.trials)

    @work(thread=True, exclusive=True, group="evaluation", exit_on_error=False)
    def _evaluate(self, trials: int) -> None:

        report = evaluate_model(open_model(self.model), trials=trials, on_progress=self._progress)
        self.post_message(EvaluationDone(report))

    def _progress(self, fraction: float) -> None:
        # From the worker thread, about once per simulated second: one message per percent.
        percent = int(fraction * 100)
        if percent != self._shown_percent:
            self._shown_percent = percent
            self.post_message(EvaluationProgress(fraction))

    def on_evaluation_progress(self, message: EvaluationProgress) -> None:
        if self.running:
            self._show_job(self.job.advanced(message.fraction * 100))

    def on_evaluation_done(self, message: EvaluationDone) -> None:
        self.report = message.report
        table = self.query_one("#evaluation-results", DataTable)
        table.clear()
        for cells in report_cells(message.report):
            table.add_row(*cells)
        self.query_one("#evaluation-summary", Static).update(summary_text(message.report))
        report = message.report
        laps = f"{report.laps} of {counted(len(report.trials), 'trial')} completed the lap"
        self._show_job(self.job.finished(laps, wall=time.time()))

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        worker = event.worker
        if worker.group != "evaluation" or worker.state is not WorkerState.ERROR:
            return
        event.prevent_default()  # shown on the job line, not as a passing notification
        assert worker.error is not None
        fix = "Press ctrl+e to try again, or Esc to go back."  # works from any field
        self._show_job(self.job.failed(error_message(worker.error), fix, wall=time.time()))

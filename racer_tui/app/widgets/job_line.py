"""Draws one `Job` (racer_tui.app.jobs): a line saying what it is doing or how it ended, a
Textual progress bar with its ETA while it runs, and, when it failed, the error in the
racer's words and the key that fixes it."""

from __future__ import annotations

import time

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.widgets import ProgressBar, Static

from racer_tui.app.jobs import Job, JobState


def local_clock(wall: float) -> str:
    return time.strftime("%H:%M", time.localtime(wall))


def job_text(job: Job) -> Text:
    """The line above the bar."""
    if job.state is JobState.RUNNING:
        return Text(f"{job.what}…")
    if job.state is JobState.DONE:
        done = Text(f"Done at {local_clock(job.at)}", style="bold green")
        return done + Text(f": {job.outcome}" if job.outcome else ".")
    if job.state is JobState.FAILED:
        failed = Text(f"Failed at {local_clock(job.at)}: ", style="bold red")
        return failed + Text(f"{job.outcome} {job.fix}".strip())
    if job.state is JobState.STOPPED:
        return Text(f"Stopped at {local_clock(job.at)}; nothing was kept.", style="yellow")
    return Text(job.what, style="dim")


class JobLine(Vertical):
    """`show(job)` after every change; the bar shows only while the job runs (after it, a
    stopped bar would say nothing the line does not)."""

    DEFAULT_CSS = """
    JobLine { height: auto; }
    JobLine > #job-text { height: auto; }
    JobLine > Horizontal { height: 1; display: none; }
    JobLine.-running > Horizontal { display: block; }
    JobLine.-idle { display: none; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.job = Job()

    def compose(self) -> ComposeResult:
        yield Static(id="job-text")
        with Horizontal():
            yield ProgressBar(id="job-bar", show_eta=True)

    def on_mount(self) -> None:
        self.show(self.job)

    def show(self, job: Job) -> None:
        self.job = job
        self.set_class(job.state is JobState.IDLE, "-idle")
        self.set_class(job.state is JobState.RUNNING, "-running")  # the bar shows only then
        self.query_one("#job-text", Static).update(job_text(job))
        bar = self.query_one("#job-bar", ProgressBar)
        if job.state is JobState.RUNNING:
            bar.update(total=job.total, progress=job.done)
        elif job.state is JobState.DONE:
            bar.update(total=1, progress=1)
        else:
            bar.update(total=1, progress=0)  # stopped or failed: nothing moves

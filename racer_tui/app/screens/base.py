"""What every racer-tui screen shares: one place that turns a failed worker into a message.

Heavy work (reading model folders, importing, exporting, racing) runs in thread workers
that either post a typed, past-tense message when they succeed or raise. A raised error
lands here: the library's user errors are already one sentence saying what to do, so they
are shown as they are; anything else is a bug, shown without a traceback and with a
request to report it. The app keeps running either way.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar, runtime_checkable

from textual import events
from textual.app import App
from textual.message import Message
from textual.screen import ModalScreen, Screen
from textual.widget import Widget
from textual.worker import Worker, WorkerState

from racer_tui.app.jobs import Job, JobState, sentence
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.words import with_app_fix
from sim.foundation.remedies import RemedyError


def error_message(error: BaseException) -> str:
    """One sentence for the racer, never a traceback."""
    if isinstance(error, RemedyError):  # its remedy in the app's words, or none of the CLI's
        text = with_app_fix(error.problem, error.fix)
        if text is None:
            return sentence(error.problem) if error.problem != str(error) else sentence(str(error))
        return text[:1].upper() + text[1:]
    if isinstance(error, ValueError):  # a library's check of a value the racer gave
        text = str(error)
        return text[:1].upper() + text[1:]
    if isinstance(error, OSError):
        where = f"{error.filename}: " if error.filename else ""
        return f"{where}{error.strerror or error}; check the path and its permissions."
    return (
        f"Something went wrong ({type(error).__name__}: {error}). "
        "The app keeps running; please report this."
    )


def notify_worker_failure(screen: Screen[Any], worker: Worker[Any]) -> None:
    if worker.state is WorkerState.ERROR and worker.error is not None:
        screen.notify(error_message(worker.error), severity="error", timeout=10, markup=False)


class ScreenJobs:
    """A screen's own jobs (imports, exports, clones, deletes) on its job line, one at a
    time so the line always speaks of the one that runs. A job's worker runs in `group`;
    when it fails the line keeps the failure, with the key that tries again, after the
    screen's notification fades."""

    def __init__(self, screen: Screen[Any], line: str, group: str) -> None:
        self._screen = screen
        self._line = line
        self.group = group
        self.job = Job()
        self._fix = ""  # the key that tries the running job again, if it fails

    def busy(self) -> bool:
        """True (and a warning) while a job runs."""
        if self.job.state is JobState.RUNNING:
            self._screen.notify(
                f"{self.job.what} is still running; try again when it is done.",
                severity="warning",
                markup=False,
            )
            return True
        return False

    def begin(self, what: str, fix_key: str) -> None:
        self._fix = f"Press {fix_key} to try again."
        now, wall = time.monotonic(), time.time()
        self._show(self.job.running(what, total=None, now=now, wall=wall))

    def finish(self, outcome: str) -> None:
        self._show(self.job.finished(outcome, wall=time.time()))

    def worker_changed(self, worker: Worker[Any]) -> None:
        """A worker's end, from the screen's `on_worker_state_changed` (whose base handler
        still notifies a failure)."""
        if worker.group != self.group:
            return
        if worker.state is WorkerState.ERROR:
            error = worker.error
            text = error_message(error) if error is not None else "It stopped."
            self._show(self.job.failed(text, self._fix, wall=time.time()))
        elif worker.state is WorkerState.CANCELLED:
            self._show(self.job.stopped(wall=time.time()))  # never left "running"

    def _show(self, job: Job) -> None:
        self.job = job
        self._screen.query_one(self._line, JobLine).show(job)


ResultT = TypeVar("ResultT")


@runtime_checkable
class Reopenable(Protocol):
    def reset(self) -> None:
        """Back to how the screen looks when it opens (a kept screen is opened again)."""


def kept_screen(app: App[Any], name: str, make: Callable[[], Screen[Any]]) -> Screen[Any]:
    """The screen the app keeps under `name`, made by `make` the first time, ready to show.

    Composing and laying out a screen afresh is most of what opening it costs (80-150 ms
    at 80x24 for the help's tables or the Sync screen's, twice that beside a training; a
    third of a question dialog's 50 ms), so a screen opened often is made once and shown
    again, `reset()` first when it has one. A fresh one is made only while the kept one is
    already open (under another section, or below a screen it opened).
    """
    if not app.is_screen_installed(name):
        app.install_screen(make(), name)
    kept = app.get_screen(name)
    if any(kept in stack for stack in app._screen_stacks.values()):
        return make()
    if isinstance(kept, Reopenable):
        kept.reset()
    return kept


def push_kept(app: App[Any], name: str, make: Callable[[], Screen[Any]]) -> None:
    """Show the screen the app keeps under `name` (see `kept_screen`)."""
    app.push_screen(kept_screen(app, name, make))


@dataclass
class ModelAdded(Message):
    """A model was created or imported outside the garage: the app shows it there."""

    name: str


def _app_style_context(screen: Screen[Any]) -> tuple[object, ...]:
    """What the app's styling of a screen rests on: the stylesheet's version (bumped by a
    theme or CSS change), whether the terminal has focus, the app's classes."""
    app = screen.app
    return (app._css_update_count, app.app_focus, tuple(sorted(app.classes)))


class _RestyledOnlyWhenNeeded:
    """Textual restyles every node of a screen each time it is shown, even just after
    mounting styled them all: a third of a section switch's work, and 10-20 ms of opening
    a dialog. A switch already restyles after a theme or CSS change (App.switch_mode
    compares the CSS version), and a screen's own nodes restyle as their classes change,
    hidden or not; so when the app's styling context is what it was when the screen was
    mounted or left, showing it skips the restyle."""

    _style_context: tuple[object, ...] | None = None

    def _on_mount(self, event: events.Mount) -> None:
        assert isinstance(self, Screen)
        self._style_context = _app_style_context(self)

    def _on_screen_suspend(self) -> None:
        assert isinstance(self, Screen)
        self._style_context = _app_style_context(self)

    def _on_screen_resume(self, event: events.ScreenResume) -> None:
        assert isinstance(self, Screen)
        if event.refresh_styles and self._style_context == _app_style_context(self):
            event.prevent_default()  # Screen's own handler, with the restyle, is not run
            Screen._on_screen_resume(self, events.ScreenResume(refresh_styles=False))


class RacerScreen(_RestyledOnlyWhenNeeded, Screen[ResultT]):
    """A full screen whose failed workers become error notifications."""

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        notify_worker_failure(self, event.worker)


class RacerModal(_RestyledOnlyWhenNeeded, ModalScreen[ResultT]):
    """A dialog whose failed workers become error notifications; it opens at its top."""

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        notify_worker_failure(self, event.worker)

    # Textual focuses a new screen's first field itself, and scrolls a newly focused widget
    # to the centre when it cannot yet see all of it: a dialog not laid out yet, taller
    # than the terminal (60x20), then opened scrolled past its title. Dialogs focus their
    # field without that scroll instead (`focus_first`), the first focusable by default.
    AUTO_FOCUS = ""  # none (None would mean the app's, which is the first focusable)

    def on_mount(self) -> None:
        if self.focused is None:  # the dialog focused none itself: Textual's choice
            first = next((widget for widget in self.query("*") if widget.focusable), None)
            if first is not None:
                self.focus_first(first)

    def focus_first(self, field: Widget) -> None:
        """Focus `field` as the dialog opens (now, not after the queue), leaving the
        dialog at its top."""
        self.set_focus(field, scroll_visible=False)

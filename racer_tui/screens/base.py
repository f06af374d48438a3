"""What every racer-tui screen shares: one place that turns a failed worker into a message.

Heavy work (reading model folders, importing, exporting, racing) runs in thread workers
that either post a typed, past-tense message when they succeed or raise. A raised error
lands here: the library's user errors are already one sentence saying what to do, so they
are shown as they are; anything else is a bug, shown without a traceback and with a
request to report it. The app keeps running either way.
"""

from __future__ import annotations

from typing import Any, TypeVar

from textual.message import Message
from textual.screen import ModalScreen, Screen
from textual.worker import Worker, WorkerState

from sim.reward_function import RewardFunctionError

# The libraries' error types are ValueErrors whose text is written for the racer.
USER_ERRORS: tuple[type[BaseException], ...] = (ValueError, RewardFunctionError)


def error_message(error: BaseException) -> str:
    """One sentence for the racer, never a traceback."""
    if isinstance(error, USER_ERRORS):
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


ResultT = TypeVar("ResultT")


class ModelAdded(Message):
    """A model was created or imported outside the garage: the app shows it there."""

    def __init__(self, name: str) -> None:
        super().__init__()
        self.name = name


class RacerScreen(Screen[ResultT]):
    """A full screen whose failed workers become error notifications."""

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        notify_worker_failure(self, event.worker)


class RacerModal(ModalScreen[ResultT]):
    """A dialog whose failed workers become error notifications."""

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        notify_worker_failure(self, event.worker)

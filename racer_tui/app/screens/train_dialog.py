"""The question before a training: its time budget, and the cars it trains among, if any
(`racer-tui train --opponent`, docs/racers/head-to-head.md): a racer preparing for a
bracket names a rival's model, a bundle file or `reference`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import Button, Input, Label, Static

from racer_tui.app.screens.dialogs import FormDialog, NameInput, show_problem

OPPONENTS_HINT = (
    "Opponents, if any: garage models, .racer-bundle files or reference, separated by "
    "commas; they drive on the track with every training car (up to 5)."
)


@dataclass(frozen=True)
class TrainAnswer:
    minutes: float
    opponents: tuple[str, ...]


def split_opponents(text: str) -> tuple[str, ...]:
    """The cars typed, in order, each named once."""
    named = [part.strip() for part in text.split(",")]
    return tuple(dict.fromkeys(name for name in named if name))


class TrainDialog(FormDialog[TrainAnswer]):
    """Minutes, then opponents (Tab reaches them); Enter in either field trains, as the
    budget's Enter always did: most trainings name no opponent. `minutes_problem` and
    `opponents_problem` say what is wrong with a field, or None."""

    COMPACT_FIELDS_BELOW_ROWS = 24  # two fields and their words fit 60x20 one row high

    def __init__(
        self,
        name: str,
        minutes: float,
        *,
        minutes_problem: Callable[[str], str | None],
        opponents_problem: Callable[[tuple[str, ...]], str | None],
    ) -> None:
        super().__init__()
        self._name = name
        self._minutes = minutes
        self._minutes_problem = minutes_problem
        self._opponents_problem = opponents_problem

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(f"Train {self._name}"), classes="dialog-title")
            yield Static(
                Text(
                    "Time budget in minutes (DeepRacer's stop condition). Training resumes "
                    "from the model's last checkpoint when it has one."
                ),
                classes="dialog-body",
            )
            yield NameInput(f"{self._minutes:g}", id="minutes")
            yield Static(Text(OPPONENTS_HINT), classes="dialog-body")
            yield NameInput("", placeholder="none: alone on the track", id="opponents")
            yield from self.form_buttons("Train")

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#minutes", Input))

    @on(Input.Submitted)
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        minutes = self.query_one("#minutes", Input).value.strip()
        opponents = split_opponents(self.query_one("#opponents", Input).value)
        problem = "Type the time budget first." if not minutes else None
        field = "#minutes"
        if problem is None:
            problem = self._minutes_problem(minutes)
        if problem is None and opponents:
            problem, field = self._opponents_problem(opponents), "#opponents"
        if problem is not None:
            show_problem(self.query_one("#problem", Static), problem)
            self.query_one(field, Input).focus()
            return
        self.dismiss(TrainAnswer(float(minutes), opponents))

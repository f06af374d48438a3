"""The first-run screen: what racer-tui is, a live demo race, and the way to a first model.

Shown when the garage is empty. The demo is the reference driver lapping the default
training track, so there is something moving on screen before anything has been trained.
"""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import Button, Static

from racer_tui.app.screens.base import ModelAdded, RacerScreen, ScreenJobs
from racer_tui.app.screens.garage import (
    ModelImported,
    import_model_dialog,
    notify_imported,
)
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.widgets.demo_race import DemoRace
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.job_line import JobLine
from racer_tui.app.widgets.section_header import SectionHeader
from sim.garage.options import DEFAULT_TRACK
from sim.tracks.catalog import resolve_track

INTRO = (
    "Build a car model the way the AWS DeepRacer console does, train it on your own "
    "computer, and race it in your league's time trials.\n\n"
)
STEPS = (
    ("1", "Create a model", "in the editor"),
    ("2", "Train it", "minutes, on the CPU"),
    ("3", "Evaluate it", "DeepRacer trials"),
    ("4", "Race it", "4:00, penalties"),
)


def intro_text() -> Text:
    text = Text(INTRO)
    for number, title, detail in STEPS:
        text.append(f" {number} ", style="bold reverse")
        text.append(f" {title}", style="bold")
        text.append(f"  {detail}\n", style="dim")
    text.rstrip()
    return text


class WelcomeScreen(RacerScreen[None]):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("n", "new_model", "Create your first model", tooltip="Open the model editor"),
        Binding("i", "import_model", "Import a model", tooltip="A DeepRacer folder or a bundle"),
    ]

    def compose(self) -> ComposeResult:
        yield SectionHeader(None)
        with Horizontal(id="welcome-body"):
            with VerticalScroll(id="welcome-text"):
                yield Static(Text("Welcome to racer-tui", style="bold"), id="welcome-title")
                yield Static(intro_text(), id="welcome-intro")
                yield Button("Create your first model (n)", id="welcome-new", variant="primary")
                yield Button("Import a DeepRacer model (i)", id="welcome-import")
                yield JobLine(id="welcome-job")
            with Vertical(id="welcome-demo"):
                yield DemoRace(resolve_track(DEFAULT_TRACK), id="demo")
        yield RacerFooter()

    def __init__(self) -> None:
        super().__init__()
        self.jobs = ScreenJobs(self, "#welcome-job", "welcome-import")  # the last import

    def on_mount(self) -> None:
        self.query_one("#welcome-new", Button).focus()

    @on(Button.Pressed, "#welcome-new")
    def action_new_model(self) -> None:
        self.app.push_screen(ModelEditorScreen(), self._model_ready)

    @on(Button.Pressed, "#welcome-import")
    def action_import_model(self) -> None:
        if self.jobs.busy():
            return
        self.app.push_screen(import_model_dialog(self), self._imported)

    def _imported(self, message: ModelImported | None) -> None:
        if message is not None:
            self.jobs.finish(f"Imported {message.name}.")
            notify_imported(self, message)
            self._model_ready(message.name)

    def _model_ready(self, name: str | None) -> None:
        if name is not None:
            self.post_message(ModelAdded(name))

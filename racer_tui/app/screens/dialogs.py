"""Small dialogs: confirm a destructive action, type a name, type a path.

Each returns its answer through `dismiss` (None when cancelled), so the caller decides what
happens next. Checks done here are the cheap ones (empty input, a name's characters); the
library checks again when the real work runs.
"""

from __future__ import annotations

import os
import unicodedata
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, TypeVar

from rich.text import Text
from textual import events, on, work
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.suggester import Suggester
from textual.widgets import Button, Checkbox, Input, Label, Select, Static

from racer_tui.app.screens.base import RacerModal, error_message, kept_screen
from sim.foundation.names import NAME_RULE, is_valid_name
from sim.foundation.remedies import echoed, echoed_path

MAX_PATH_SUGGESTIONS = 200  # a huge folder is not listed in full while typing


def show_problem(line: Static, problem: str) -> None:
    line.update(Text(problem))
    line.set_class(bool(problem), "-shown")
    if problem:  # a long form scrolls at 80x24: bring the sentence into view, once drawn
        line.call_after_refresh(line.scroll_visible, animate=False)


class NameInput(Input):
    """An Input that keeps the invisible characters typed into it (U+202E and the other
    bidi and format controls), so the field's check refuses them in the same sentence as
    the command line. Textual's Input drops a typed character that is not printable
    without a word: `abc<U+202E>def` became `abcdef` in the app while the command line
    refused it (issue 42). A paste keeps them already."""

    async def _on_key(self, event: events.Key) -> None:
        character = event.character
        if character is None or event.is_printable or len(character) != 1:
            return  # Input's own handler, next in line, does what it always does
        if unicodedata.category(character) != "Cf":
            return  # control keys (Esc, Tab, ctrl+…) are keys, not text
        event.stop()
        event.prevent_default()  # Input's handler would drop it
        selection = self.selection
        if selection.is_empty:
            self.insert_text_at_cursor(character)
        else:
            self.replace(character, *selection)


class PathSuggester(Suggester):
    """Completes the last part of a file system path, like a shell's Tab."""

    def __init__(self) -> None:
        super().__init__(use_cache=False, case_sensitive=True)

    async def get_suggestion(self, value: str) -> str | None:
        if not value:
            return None
        expanded = os.path.expanduser(value)
        folder, _, start = expanded.rpartition(os.sep)
        directory = Path(folder or (os.sep if expanded.startswith(os.sep) else "."))
        try:
            with os.scandir(directory) as entries:
                names = sorted(
                    entry.name + (os.sep if entry.is_dir() else "")
                    for _, entry in zip(range(MAX_PATH_SUGGESTIONS), entries, strict=False)
                    if entry.name.startswith(start) and not entry.name.startswith(".")
                )
        except OSError:
            return None
        # Like a shell: as far as every match agrees (one match: all of it), never the first
        # of several that differ (/tmp/wa must not become /tmp/walk/ when /tmp/walk2 is there).
        shared = os.path.commonprefix(names)  # noqa: RUF071 - names in one folder, by character
        if len(shared) <= len(start):
            return None
        return value + shared[len(start) :]


class NameOrPathSuggester(Suggester):
    """Completes a name from a list, or, once the value looks like a path (it starts with
    /, ~ or .), the last part of that path."""

    def __init__(self, names: list[str]) -> None:
        super().__init__(use_cache=False, case_sensitive=True)
        self._names = names
        self._paths = PathSuggester()

    async def get_suggestion(self, value: str) -> str | None:
        if value.startswith(("/", "~", ".")):
            return await self._paths.get_suggestion(value)
        return next((name for name in self._names if name.startswith(value) and value), None)


class ConfirmDialog(RacerModal[bool]):
    """Yes or no, with the consequence spelled out. Enter never confirms by accident:
    the focus is on Cancel each time the question is shown. Ask through `ask`, which
    shows the app's one kept question dialog."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("y", "answer(True)", "Yes"),
        Binding("n,escape", "answer(False)", "No"),
    ]

    def __init__(
        self,
        title: str,
        message: str,
        confirm_label: str = "Delete",
        cancel_label: str = "Cancel",
    ) -> None:
        super().__init__()
        self._title = title
        self._message = message
        self._confirm_label = confirm_label
        self._cancel_label = cancel_label

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(self._title), classes="dialog-title", id="question-title")
            yield Static(Text(self._message), classes="dialog-body", id="question-body")
            with Horizontal(classes="dialog-buttons"):
                yield Button(f"{self._cancel_label} (n)", id="cancel")
                yield Button(f"{self._confirm_label} (y)", id="confirm", variant="error")

    def pose(
        self, title: str, message: str, confirm_label: str, cancel_label: str = "Cancel"
    ) -> None:
        """Ask this question next time the dialog is shown."""
        self._title, self._message = title, message
        self._confirm_label, self._cancel_label = confirm_label, cancel_label
        if self.is_mounted:  # a kept dialog shows its new question; a new one composes it
            self.query_one("#question-title", Label).update(Text(title))
            self.query_one("#question-body", Static).update(Text(message))
            labels = {"#confirm": f"{confirm_label} (y)", "#cancel": f"{cancel_label} (n)"}
            for selector, label in labels.items():
                button = self.query_one(selector, Button)
                button.label = label
                # A button keeps the width of its last label when only the label changes:
                # "Close night (y)" after "Delete (y)" wrapped into "Close night".
                button.refresh(layout=True)

    def on_screen_resume(self) -> None:
        self.query_one("#cancel", Button).focus()

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)

    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        self.dismiss(True)

    @on(Button.Pressed, "#cancel")
    def _cancel(self) -> None:
        self.dismiss(False)


QUESTION_SCREEN = "question"


def ask(
    app: App[Any],
    title: str,
    message: str,
    answered: Callable[[bool | None], None],
    *,
    confirm_label: str = "Delete",
    cancel_label: str = "Cancel",
) -> None:
    """Ask a yes-or-no question in the app's kept question dialog; `answered` gets the
    answer (True for yes) once the racer gives it. `cancel_label` names the no when it does
    more than cancel (start a heat again, keep watching)."""
    dialog = kept_screen(app, QUESTION_SCREEN, lambda: ConfirmDialog(title, message))
    assert isinstance(dialog, ConfirmDialog)
    dialog.pose(title, message, confirm_label, cancel_label)
    app.push_screen(dialog, answered)


RequestT = TypeVar("RequestT")


class FormDialog(RacerModal[RequestT | None]):
    """A dialog with fields, a problem line and Cancel/confirm buttons; Esc cancels."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "cancel", "Cancel"),
        # As in the model editor and the night dialog: every form confirms on Ctrl+S.
        Binding("ctrl+s", "confirm_form", "Confirm", show=False, priority=True),
    ]
    # A form whose three-row fields do not fit a terminal shorter than this gets one-row
    # fields there, so it shows whole, buttons included, without scrolling (0: never).
    COMPACT_FIELDS_BELOW_ROWS: ClassVar[int] = 0

    def on_resize(self) -> None:
        short = self.app.size.height < self.COMPACT_FIELDS_BELOW_ROWS
        for field in self.query("Input, Select").results():
            if isinstance(field, Input | Select):
                field.compact = short

    @on(Input.Changed)
    def _problem_answered(self) -> None:
        """A problem said is about what was typed then: once the racer changes a field it
        is no longer the news (the next confirm checks again)."""
        line = self.query("#problem").first(Static) if self.query("#problem") else None
        if line is not None and line.has_class("-shown"):
            show_problem(line, "")

    def form_buttons(self, confirm_label: str) -> ComposeResult:
        """The problem line and the button row every form ends with."""
        yield Static("", id="problem", classes="field-problem")
        with Horizontal(classes="dialog-buttons"):
            yield Button("Cancel (esc)", id="cancel")
            yield Button(confirm_label, id="confirm", variant="primary")

    def action_cancel(self) -> None:
        self.dismiss(None)

    def action_confirm_form(self) -> None:
        """Ctrl+S: what the confirm button does, from whichever field has the focus."""
        confirm = self.query("#confirm")
        if confirm:
            confirm.first(Button).press()

    @on(Button.Pressed, "#cancel")
    def _cancel(self) -> None:
        self.dismiss(None)


class InputDialog(FormDialog[str]):
    """One line of input. `check` returns a problem to show under the field, or None."""

    def __init__(
        self,
        title: str,
        message: str,
        *,
        value: str = "",
        placeholder: str = "",
        confirm_label: str = "OK",
        check: Callable[[str], str | None] | None = None,
        paths: bool = False,
    ) -> None:
        super().__init__()
        self._title = title
        self._message = message
        self._value = value
        self._placeholder = placeholder
        self._confirm_label = confirm_label
        self._check = check
        self._paths = paths

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(self._title), classes="dialog-title")
            yield Static(Text(self._message), classes="dialog-body")
            yield NameInput(
                self._value,
                placeholder=self._placeholder,
                suggester=PathSuggester() if self._paths else None,
                id="answer",
            )
            yield from self.form_buttons(self._confirm_label)

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#answer", Input))

    @on(Input.Submitted)
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        answer = self.query_one("#answer", Input).value.strip()
        problem = "Type something first." if not answer else None
        if problem is None and self._check is not None:
            problem = self._check(answer)
        if problem is not None:
            show_problem(self.query_one("#problem", Static), problem)
            self.query_one("#answer", Input).focus()
            return
        self.dismiss(answer)


@dataclass(frozen=True)
class ImportRequest:
    path: str
    name: str | None  # None: the folder's (or bundle's) own name
    untrained: bool = False  # a DeepRacer folder's own weights are left behind


WorkT = TypeVar("WorkT")


@dataclass
class WorkDone(Message):
    """A dialog's work (an import) is done: the dialog closes with its result."""

    result: object


@dataclass
class WorkFailed(Message):
    """A dialog's work failed: the dialog stays open and says why."""

    error: BaseException


class PathNameDialog(FormDialog[WorkT]):
    """A path (→ completes it) and an optional new name, then the work itself (an import)
    run from the dialog: what stops it (a name that is taken, a file that cannot be used,
    a folder that is no DeepRacer model) is said under the fields, with what was typed still
    there to change. The dialog closes with the work's result once it is done.

    `work` runs in a thread; `ask_first`, when given, may ask a question before it runs
    (`go` runs it; not calling it leaves the dialog open as it was)."""

    TITLE = ""
    BODY = ""
    PATH_PLACEHOLDER = ""
    NAME_PLACEHOLDER = ""
    UNTRAINED_LABEL = ""  # a box to leave a model's own weights behind, when not empty
    CONFIRM_LABEL = "Import"
    WORKING_LABEL = "Importing…"

    def __init__(
        self,
        work: Callable[[ImportRequest], WorkT],
        path: str = "",
        *,
        ask_first: Callable[[ImportRequest, Callable[[ImportRequest], None]], None] | None = None,
    ) -> None:
        super().__init__()
        self._work = work
        self._path = path
        self._ask_first = ask_first
        self.working = False

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(self.TITLE, classes="dialog-title")
            yield Static(self.BODY, classes="dialog-body")
            yield NameInput(
                self._path,
                placeholder=self.PATH_PLACEHOLDER,
                suggester=PathSuggester(),
                id="path",
            )
            yield NameInput(placeholder=self.NAME_PLACEHOLDER, id="name")
            if self.UNTRAINED_LABEL:
                yield Checkbox(self.UNTRAINED_LABEL, id="untrained", compact=True)
            yield from self.form_buttons(self.CONFIRM_LABEL)

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#path", Input))

    def problem(self, path: str, name: str | None) -> str | None:
        """What is wrong with the path or the name, or None (the cheap checks, before the
        work runs)."""
        raise NotImplementedError

    @on(Input.Submitted)
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        if self.working:
            return
        path = self.query_one("#path", Input).value.strip()
        name = self.query_one("#name", Input).value.strip() or None
        problem = self.problem(path, name)
        if problem is not None:
            show_problem(self.query_one("#problem", Static), problem)
            return
        boxes = self.query("#untrained").results(Checkbox)
        request = ImportRequest(path, name, any(box.value for box in boxes))
        if self._ask_first is not None:
            self._ask_first(request, self._start)
        else:
            self._start(request)

    def _start(self, request: ImportRequest) -> None:
        self._set_working(True)
        self._run(request)

    def _set_working(self, working: bool) -> None:
        self.working = working
        confirm = self.query_one("#confirm", Button)
        confirm.label = self.WORKING_LABEL if working else self.CONFIRM_LABEL
        confirm.disabled = working
        self.query_one("#cancel", Button).disabled = working

    @work(thread=True, exclusive=True, group="dialog-work", exit_on_error=False)
    def _run(self, request: ImportRequest) -> None:
        try:
            result: object = self._work(request)
        except Exception as error:  # every failure is said in the dialog, in one sentence
            self.post_message(WorkFailed(error))
            return
        self.post_message(WorkDone(result))

    def on_work_done(self, message: WorkDone) -> None:
        self.dismiss(message.result)  # type: ignore[arg-type]

    def on_work_failed(self, message: WorkFailed) -> None:
        self._set_working(False)
        show_problem(self.query_one("#problem", Static), error_message(message.error))
        self.query_one("#path", Input).focus()

    def action_cancel(self) -> None:
        if not self.working:  # an import half done is not left behind unseen
            super().action_cancel()


class ImportDialog(PathNameDialog[WorkT]):
    """A DeepRacer model folder, a .racer-bundle or a car archive, and optionally a name."""

    TITLE = "Import a model"
    # Its two fields framed, with the body and the check box, pushed the buttons out of
    # view at 60x20 (the host walk): one-row fields below 24 rows.
    COMPACT_FIELDS_BELOW_ROWS = 24
    BODY = (
        "A DeepRacer model folder (as DeepRacer for Cloud or the console's download lays it "
        "out), a .racer-bundle file from another racer, or a DeepRacer car archive (.tar.gz, "
        "the file a physical car loads). → completes a path."
    )
    PATH_PLACEHOLDER = "path, e.g. ~/Downloads/my-model"
    NAME_PLACEHOLDER = "model name (empty: the folder's name)"
    UNTRAINED_LABEL = "Without its DeepRacer weights, to train it here"  # fits 60 columns

    def problem(self, path: str, name: str | None) -> str | None:
        if not path:
            return "Give the path of a DeepRacer model folder, a .racer-bundle or a .tar.gz file."
        if not _exists(path):
            return (
                f"{echoed_path(path)} does not exist or cannot be read; check the path "
                "(→ completes it)."
            )
        if name and not is_valid_name(name):
            return f"{echoed(name)} cannot be a model name; use {NAME_RULE}."
        return None


def _exists(path: str) -> bool:
    """Whether a typed path exists; False for one that cannot even be looked at (an
    unknown ~user, a folder this user may not read) rather than an error."""
    try:
        return Path(path).expanduser().exists()
    except (OSError, RuntimeError):
        return False

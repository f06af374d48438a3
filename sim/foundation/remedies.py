"""Remedies that a sentence for the user ends with, named so that each front end can say
them its own way: the library writes the command line's words (`racer-tui tracks import
FILE`), and the app, which does the same with a key, says that instead
(`racer_tui.app.screens.base`)."""

from __future__ import annotations

from enum import Enum
from typing import Final

# What a sentence quotes of something the user typed or a file said: enough to recognise
# it, never a 10,000-character name repeated back whole.
ECHO_CHARS: Final = 40
# A path is shown as it is up to this length (a file's place matters more than a name's).
PATH_ECHO_CHARS: Final = 120


class Fix(Enum):
    IMPORT_TRACK = "import the track"
    TRAIN_MODEL = "train the model"
    CHOOSE_TRACK = "choose the model's track"
    RENAME = "give it another name"
    CHOOSE_MODEL = "choose or create a model"
    SET_RACER_NAME = "save this machine's racer name"
    EVALUATE_MODEL = "evaluate the model"
    IMPORT_MODEL = "import the DeepRacer model folder"
    RUN_HEATS = "run the night's waiting heats"
    CLOSE_NIGHT = "close the night"


def fix_named(name: object) -> Fix | None:
    """The remedy a file names (`Fix.X.name`), or None for none or a name this racer-tui
    does not know (files are untrusted)."""
    return Fix.__members__.get(name) if isinstance(name, str) else None


class Note(str):
    """A note for the user, as the command line prints it, that ends in a remedy: `problem`
    is the sentence without the remedy and `fix` names it. It is a `str`, so everything
    that prints, joins or serialises notes keeps working."""

    problem: str
    fix: Fix

    def __new__(cls, text: str, *, problem: str, fix: Fix) -> Note:
        note = super().__new__(cls, text)
        note.problem = problem
        note.fix = fix
        return note


class RemedyError(ValueError):
    """The one root of every error whose message is one sentence for the user: the command
    line catches it in one place (exit 2), the app in one place (`error_message`). When the
    message ends in a remedy that a front end may offer its own way, `problem` is the
    sentence without it and `fix` names it (as for a Note)."""

    def __init__(self, message: str, *, problem: str = "", fix: Fix | None = None) -> None:
        super().__init__(message)
        self.problem = problem or message
        self.fix = fix


def echoed(value: object, limit: int = ECHO_CHARS) -> str:
    """`value` quoted as a sentence for the user repeats it (its repr), cut to `limit`
    characters with an ellipsis and its length when it is longer: "'aaaa…' (10,000
    characters)"."""
    text = value if isinstance(value, str) else str(value)
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit] + '…'!r} ({len(text):,} characters)"


def echoed_path(path: object) -> str:
    """A path as a sentence names a file: as it is, or `echoed` when it is longer than
    PATH_ECHO_CHARS (no real file has a 10,000-character path)."""
    text = str(path)
    return text if len(text) <= PATH_ECHO_CHARS else echoed(text, PATH_ECHO_CHARS)

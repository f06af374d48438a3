"""The app's own words for a remedy: a library's sentence ends in what to do, written for
the command line (`racer-tui tracks import FILE`); where the app does the same with a key,
it says the key instead (`sim.foundation.remedies`)."""

from __future__ import annotations

from sim.foundation.remedies import Fix, Note

# Remedies the app offers itself, in its words: its keys, not the command line's commands.
APP_FIXES = {
    Fix.IMPORT_TRACK: "import its .npy file on the Tracks screen (i there)",
    Fix.TRAIN_MODEL: "press t in the Garage to train it",
    Fix.CHOOSE_TRACK: (
        "press e in the Garage to choose another (i on the Tracks screen imports a DeepRacer "
        ".npy track)"
    ),
    Fix.RENAME: "choose another name",
    Fix.CHOOSE_MODEL: "the Garage (1) lists your models, and n there creates one",
    Fix.SET_RACER_NAME: "submit a result under your name (u in the Garage), then sync again",
    Fix.EVALUATE_MODEL: "press v in the Garage to evaluate it",
    Fix.IMPORT_MODEL: "give a garage model's name, or import the folder in the Garage (i there)",
    Fix.RUN_HEATS: "run them (r), or press c again to close the night anyway",
    Fix.CLOSE_NIGHT: "close it instead (c): its results stay in the league",
}


def in_app_words(note: str) -> str:
    """A library's note as the app says it: a remedy the app offers with a key is named by
    its key, not by its command."""
    if isinstance(note, Note):
        return with_app_fix(note.problem, note.fix) or note
    return note


def with_app_fix(problem: str, fix: Fix | None) -> str | None:
    """The problem with the app's own remedy, or None when the app offers none."""
    return f"{problem}; {APP_FIXES[fix]}." if fix in APP_FIXES else None


def said_in_app(message: str, problem: str, fix: Fix | None) -> str:
    """A message the library also gave apart (`problem`, `fix`), as the app says it: with
    the app's remedy when it has one, else as the library wrote it."""
    return (with_app_fix(problem, fix) if problem else None) or message

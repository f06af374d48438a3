"""The app's sections: the places a racer moves between with one key.

One list, read by the app (its modes and keys), the header (the tabs it draws) and the
command palette (its "Go to ..." commands), so adding a section is one line here plus its
screen in `racer_tui.app.application`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Section:
    mode: str  # the Textual mode name
    title: str  # shown in the header and the palette
    key: str  # the key that switches to it
    summary: str  # one line for the palette and the help screen


SECTIONS: tuple[Section, ...] = (
    Section("garage", "Garage", "1", "your models: create, edit, clone, import, race"),
    Section("tracks", "Tracks", "2", "the built-in and imported tracks, with reference laps"),
    Section(
        "races",
        "Races",
        "3",
        "time trials of any trained model or the reference driver, and head-to-head races",
    ),
    Section("training", "Training", "4", "train models in the background with live charts"),
    Section("league", "League", "5", "leaderboard, league nights and the projector"),
)
WELCOME_MODE = "welcome"


def section_for(mode: str) -> Section | None:
    return next((section for section in SECTIONS if section.mode == mode), None)

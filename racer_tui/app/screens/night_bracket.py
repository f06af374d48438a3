"""A night's knock-out bracket in the app: the host draws it on the Nights screen (k) once
the heats are raced, and races its next match live (r), which is recorded as the night's
match when the host leaves the race view (league.bracket_nights)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path

from textual import on
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.message import Message
from textual.widgets import Button, Input, Label, Static

from league.bracket_nights import MatchCars, match_entries, match_seed
from league.bracket_records import NightBracket
from league.bracket_rounds import match_title
from league.brackets import MAX_ENTRANTS, MIN_ENTRANTS, Format
from league.live_match import LiveMatchWriter, live_match_path
from league.nights import Night
from league.store import default_db_path
from racer_tui.app.screens.dialogs import FormDialog, show_problem
from racer_tui.app.screens.form_select import FormSelect
from racer_tui.app.screens.head_to_head_screen import HeadToHeadSetup
from sim.race.rules import HEAD_TO_HEAD_RULES
from sim.tracks.track import Track
from sim.training.drivers import resolve_driver

MAX_MATCH_LAPS = 99
FORMAT_CHOICES = (
    ("single elimination: out after one loss", Format.SINGLE.value),
    ("double elimination: out after two", Format.DOUBLE.value),
)


@dataclass(frozen=True)
class BracketRequest:
    size: int | None  # None: every racer with a counting result
    format: Format
    laps: int


class DrawBracketDialog(FormDialog[BracketRequest]):
    """How many qualifiers the bracket seeds, single or double elimination, and each
    match's laps."""

    COMPACT_FIELDS_BELOW_ROWS = 30

    def __init__(self, qualified: int = MAX_ENTRANTS) -> None:
        """`qualified`: the racers the night's standings can seed."""
        super().__init__()
        self.qualified = qualified

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label("Draw the bracket", classes="dialog-title")
            yield Static(
                "The night's standings seed a knock-out, best first; each match is a "
                "head-to-head race of two cars, the first past the line going on. From then "
                "on the night takes no entrants and no draws.",
                classes="dialog-body",
            )
            yield Label(f"Qualifiers, 2 to {min(self.qualified, MAX_ENTRANTS)} (empty: all)")
            yield Input(placeholder="every qualifier", id="bracket-size")
            yield Label("Format")
            yield FormSelect(FORMAT_CHOICES, value=Format.SINGLE.value, id="bracket-format")
            yield Label("Laps of each match")
            yield Input(str(HEAD_TO_HEAD_RULES.lap_count), id="bracket-laps")
            yield from self.form_buttons("Draw")

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#bracket-size", Input))

    @on(Input.Submitted, "#bracket-size")
    def _next_field(self) -> None:
        self.query_one("#bracket-format", FormSelect).focus()

    @on(Input.Submitted, "#bracket-laps")
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        size_text = self.query_one("#bracket-size", Input).value.strip()
        laps_text = self.query_one("#bracket-laps", Input).value.strip()
        problem = None
        most = min(self.qualified, MAX_ENTRANTS)
        if size_text and not (size_text.isdigit() and MIN_ENTRANTS <= int(size_text) <= most):
            problem = (
                f"Qualifiers is a number from {MIN_ENTRANTS} to {most} (the racers with a "
                "counting result), or empty for all of them."
            )
        elif not (laps_text.isdigit() and 1 <= int(laps_text) <= MAX_MATCH_LAPS):
            problem = f"Laps is a whole number from 1 to {MAX_MATCH_LAPS}."
        if problem is not None:
            show_problem(self.query_one("#problem", Static), problem)
            return
        chosen = str(self.query_one("#bracket-format", FormSelect).value)
        self.dismiss(
            BracketRequest(int(size_text) if size_text else None, Format(chosen), int(laps_text))
        )


@dataclass
class MatchReady(Message):
    night: Night
    cars: MatchCars
    setup: HeadToHeadSetup


def match_setup(
    drawn: NightBracket, cars: MatchCars, track: Track, league_file: Path | None = None
) -> HeadToHeadSetup:
    """The race view's setup for a match: the bracket's rules and the match's own seed,
    the higher seed on the front of the grid; it tells the night's projector where the
    match is."""
    live = LiveMatchWriter(
        live_match_path(league_file or default_db_path(), drawn.night_id),
        night_id=drawn.night_id,
        match_id=cars.match.id,
        title=match_title(drawn, cars.match),
        lap_count=drawn.rules.lap_count,
        # A bundle by its file name, never its path: the venue sees it.
        racers=[(entrant.display_name, entrant.car) for entrant in (cars.first, cars.second)],
    )
    return HeadToHeadSetup(
        track=track,
        rules=drawn.rules,
        names=(cars.first.display_name, cars.second.display_name),
        entries=partial(match_entries, cars, track, resolve_driver),
        seed=match_seed(drawn, cars.match.id),
        live=live,
        match=f"{match_title(drawn, cars.match)} ({cars.match.id})",
    )

"""A night's knock-out bracket in the app: the host draws it on the Nights screen (k) once
the heats are raced, and races its next match live (r), which is recorded as the night's
match when the host leaves the race view (league.bracket_nights); a match of physical
cars is timed by hand for both cars (`MatchTimekeeperScreen`)."""

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
from league.timekeeper.car import car_name
from league.timekeeper.journal import HeatJournal, journal_path
from racer_tui.app.screens.dialogs import FormDialog, show_problem
from racer_tui.app.screens.form_select import FormSelect
from racer_tui.app.screens.head_to_head_screen import HeadToHeadSetup
from racer_tui.app.screens.match_timekeeper import (
    MatchTimekeeperSetup,
    match_car,
)
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
    physical: bool = False  # seeds the physical cars, raced on the real track


class DrawBracketDialog(FormDialog[BracketRequest]):
    """How many qualifiers the bracket seeds, single or double elimination, and each
    match's laps."""

    COMPACT_FIELDS_BELOW_ROWS = 30

    def __init__(self, qualified: int = MAX_ENTRANTS, physical: int = 0) -> None:
        """`qualified`: the racers in simulated cars the night's standings can seed;
        `physical`: those in physical cars (a bracket races one kind)."""
        super().__init__()
        self.simulated = qualified
        self.physical = physical
        # The kind with enough qualifiers to race, simulated first.
        self.kinds = [
            (label, value)
            for label, value, count in (
                (f"simulated cars ({qualified})", "simulated", qualified),
                (f"physical cars on the track ({physical})", "physical", physical),
            )
            if count >= MIN_ENTRANTS
        ]

    @property
    def qualified(self) -> int:
        """The qualifiers of the kind chosen."""
        return self.physical if self._chosen_kind() == "physical" else self.simulated

    def _left_out(self) -> str:
        """The other kind's qualifiers, too few for a bracket of their own ("": none)."""
        racing = self._chosen_kind()
        other, count = (
            ("Simulated", self.simulated) if racing == "physical" else ("Physical", self.physical)
        )
        if not count:
            return ""
        return f"{other} cars ({count}) are left out: a bracket races one kind of car."

    def _chosen_kind(self) -> str:
        if len(self.kinds) < 2 or not self.is_mounted:
            return self.kinds[0][1] if self.kinds else "simulated"
        return str(self.query_one("#bracket-kind", FormSelect).value)

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label("Draw the bracket", classes="dialog-title")
            yield Static(
                "The night's standings seed a knock-out, best first; each match is a "
                "head-to-head race of two cars, the first past the line going on (physical "
                "cars: the first to finish, penalties added). From then on the night takes "
                "no entrants and no draws.",
                classes="dialog-body",
            )
            if len(self.kinds) > 1:
                yield Label("Cars")
                yield FormSelect(self.kinds, value=self.kinds[0][1], id="bracket-kind")
            elif left_out := self._left_out():
                yield Static(left_out, classes="dialog-body")
            yield Label(self._size_label(), id="bracket-size-label")
            yield Input(placeholder="every qualifier", id="bracket-size")
            yield Label("Format")
            yield FormSelect(FORMAT_CHOICES, value=Format.SINGLE.value, id="bracket-format")
            yield Label("Laps of each match")
            yield Input(str(HEAD_TO_HEAD_RULES.lap_count), id="bracket-laps")
            yield from self.form_buttons("Draw")

    def _size_label(self) -> str:
        most = min(self.qualified, MAX_ENTRANTS)
        kind = self._chosen_kind().capitalize()
        if most == MIN_ENTRANTS:
            return f"{kind} qualifiers: {MIN_ENTRANTS} (empty: both)"
        return f"{kind} qualifiers, {MIN_ENTRANTS} to {most} (empty: all)"

    def on_mount(self) -> None:
        first = self.query("#bracket-kind") or self.query("#bracket-size")
        self.focus_first(first.first())

    @on(FormSelect.Changed, "#bracket-kind")
    def _kind_chosen(self) -> None:
        self.query_one("#bracket-size-label", Label).update(self._size_label())

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
            BracketRequest(
                int(size_text) if size_text else None,
                Format(chosen),
                int(laps_text),
                physical=self._chosen_kind() == "physical",
            )
        )


@dataclass
class MatchReady(Message):
    night: Night
    cars: MatchCars
    setup: HeadToHeadSetup | MatchTimekeeperSetup


def _live(drawn: NightBracket, cars: MatchCars, league_file: Path | None) -> LiveMatchWriter:
    """Where the match tells the night's projector how it stands."""
    return LiveMatchWriter(
        live_match_path(league_file or default_db_path(), drawn.night_id),
        night_id=drawn.night_id,
        match_id=cars.match.id,
        title=match_title(drawn, cars.match),
        lap_count=drawn.rules.lap_count,
        # A bundle by its file name, never its path: the venue sees it.
        racers=[(entrant.display_name, entrant.car) for entrant in (cars.first, cars.second)],
    )


def match_setup(
    drawn: NightBracket, cars: MatchCars, track: Track, league_file: Path | None = None
) -> HeadToHeadSetup | MatchTimekeeperSetup:
    """The match's screen setup: the race view's, with the bracket's rules and the match's
    own seed, the higher seed on the front of the grid; or, for two physical cars, the
    timekeeper's for both. Either tells the night's projector where the match is."""
    live = _live(drawn, cars, league_file)
    title = f"{match_title(drawn, cars.match)} ({cars.match.id})"
    if cars.physical:
        key = f"{drawn.night_id}-{cars.match.id}"
        return MatchTimekeeperSetup(
            track=track,
            rules=drawn.rules,
            cars=(
                match_car(cars.first.racer, car_name(cars.first.model)),
                match_car(cars.second.racer, car_name(cars.second.model)),
            ),
            names=(cars.first.display_name, cars.second.display_name),
            title=title,
            live=live,
            journal=HeatJournal(journal_path(league_file or default_db_path(), key), key, cars=2),
        )
    return HeadToHeadSetup(
        track=track,
        rules=drawn.rules,
        names=(cars.first.display_name, cars.second.display_name),
        entries=partial(match_entries, cars, track, resolve_driver),
        seed=match_seed(drawn, cars.match.id),
        live=live,
        match=title,
    )

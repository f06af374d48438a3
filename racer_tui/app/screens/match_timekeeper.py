"""A bracket match between physical cars, timed by hand: one race clock, and for each car
a lap key and a reset key, its lap clock, laps and race time, side by side.

The state machine is `league.timekeeper.match.TimekeptMatch`; this screen feeds it keys
with the moment each came, keeps its journal (a killed racer-tui resumes the match), tells
the night's projector where the match is, and returns the match's result once it is over,
which the Nights screen records as the night's match.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.widgets import Digits, Label, Static

from league.live_match import LiveCar, LiveMatchWriter
from league.timekeeper.feed import TIMER_ENV
from league.timekeeper.heat import Phase, TimekeeperError, physical_floor
from league.timekeeper.journal import HeatJournal, ResumedMatch, resume_match, take_match_input
from league.timekeeper.match import MatchCar, TimekeptMatch
from racer_tui.app.screens.hand_timing import HandTimedScreen, lap_lines
from racer_tui.app.screens.head_to_head_screen import car_colour
from racer_tui.app.screens.race_screen import countdown_text
from racer_tui.app.screens.timekeeper import CLOCK_HZ, car_hash, lap_clock_text
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.lap_list import LapList
from racer_tui.text.clocks import clock_text
from sim.race.head_to_head import HeadToHeadResult
from sim.race.rules import RaceRules
from sim.tracks.track import Track

RECORD_WITH_ESC = "Esc records the match on the night (strike a lap out first with x)."
# Each car's keys: its lap key above its reset key, the first car's on the left.
LAP_KEYS = ("1", "2")
RESET_KEYS = ("q", "w")


@dataclass(frozen=True)
class MatchTimekeeperSetup:
    track: Track
    rules: RaceRules
    cars: tuple[MatchCar, MatchCar]  # grid order: the higher seed first
    names: tuple[str, str]  # the racers as the night shows them
    title: str  # the match as racers name it: "Final (W2-1)"
    live: LiveMatchWriter | None = None  # where the night's projector reads the match
    journal: HeatJournal | None = None  # its inputs, to resume it


class MatchTimekeeperScreen(HandTimedScreen[HeadToHeadResult | None]):
    """Two physical cars' match: the race clock, and per car its lap in progress, laps,
    resets and race time, with a lap key and a reset key each."""

    RACE_WORD = "match"
    TIMING_KEYS: ClassVar[dict[str, str]] = {
        "1": "capture(0)",
        "2": "capture(1)",
        "q": "reset(0)",
        "w": "reset(1)",
    }
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("space", "start_pause", "Start/pause", priority=True),
        Binding("1", "capture(0)", "Lap car 1", priority=True),
        Binding("2", "capture(1)", "Lap car 2", priority=True),
        Binding("q", "reset(0)", "Reset car 1", priority=True),
        Binding("w", "reset(1)", "Reset car 2", priority=True),
        Binding("tab", "choose_car", "Other car", show=False, priority=True),
        Binding("u", "undo_capture", "Undo lap", show=False),
        Binding("R", "undo_reset", "Undo reset", show=False),
        Binding("f", "retire", "Retire car", show=False),
        Binding("x", "strike", "Strike lap", show=False),
        Binding("e", "end", "End race"),
        Binding("escape", "leave", "Back", show=False),
    ]
    DEFAULT_CSS = """
    MatchTimekeeperScreen #mt-title { text-style: bold; height: 1; }
    MatchTimekeeperScreen #mt-clock-row { height: 4; }
    MatchTimekeeperScreen #mt-clock { width: 1fr; height: 4; }
    MatchTimekeeperScreen #mt-state { width: 1fr; height: 4; padding: 1 0 0 2; }
    MatchTimekeeperScreen #mt-cars { height: 1fr; }
    MatchTimekeeperScreen .mt-car { width: 1fr; padding: 0 1; border-left: blank; }
    MatchTimekeeperScreen .mt-car.-chosen { border-left: thick $accent; }
    MatchTimekeeperScreen .mt-name { height: 1; text-style: bold; }
    MatchTimekeeperScreen .mt-facts { height: 3; }  /* a line each: whole at 60 columns */
    MatchTimekeeperScreen #mt-said { height: auto; max-height: 2; }
    MatchTimekeeperScreen #mt-keys { height: 2; color: $text-muted; }
    """

    def __init__(self, setup: MatchTimekeeperSetup) -> None:
        super().__init__()
        self.setup = setup
        self.floor_seconds = physical_floor(setup.track)
        self.match = TimekeptMatch(setup.rules, len(setup.cars), floor_seconds=self.floor_seconds)
        self.clock: Callable[[], float] = time.monotonic  # a test may drive its own clock
        self.chosen = 0  # the car undo, retire and strike act on (Tab: the other)
        self.said = Text("Space starts the race when the cars leave the line.", style="dim")
        self._origin: float | None = None  # the match runs on its own time, as a heat does
        self.journal = setup.journal
        self._laps_shown: list[tuple[bool, ...] | None] = [None] * len(setup.cars)
        self._facts_shown: list[Text | None] = [None] * len(setup.cars)

    def compose(self) -> ComposeResult:
        setup = self.setup
        yield Static(
            Text(f"{setup.title}: {' v '.join(setup.names)}, on {setup.track.name}"),
            id="mt-title",
        )
        with Horizontal(id="mt-clock-row"):
            with Vertical(id="mt-clock"):
                yield Label("Time left")
                yield Digits(countdown_text(setup.rules.window_seconds), id="mt-left")
            yield Static(id="mt-state")
        with Horizontal(id="mt-cars"):
            for k in range(len(setup.cars)):
                with Vertical(classes="mt-car", id=f"mt-car-{k}"):
                    yield Static(classes="mt-name", id=f"mt-name-{k}")
                    yield Static(classes="mt-facts", id=f"mt-facts-{k}")
                    yield LapList(id=f"mt-laps-{k}")
        yield Static(id="mt-said")
        yield Static(self._keys_text(), id="mt-keys")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.set_interval(1.0 / CLOCK_HZ, self._draw_clocks)
        self._choose(0)
        self._draw()
        if os.environ.get(TIMER_ENV):
            self._say(
                "The automatic timer cannot tell two cars apart, so it is not read here: "
                "time this match by keys (1 2 lap, q w reset)."
            )
        journal = self.journal
        if journal is not None:
            resumed = resume_match(
                journal.path,
                journal.heat_id,
                self.setup.rules,
                len(self.setup.cars),
                floor_seconds=self.floor_seconds,
            )
            if resumed is not None:
                self._offer_to_resume(resumed)

    def on_unmount(self) -> None:
        if self.journal is not None:
            self.journal.close()  # the file stays: the match may be resumed
        if self.setup.live is not None:
            self.setup.live.clear()

    def _offer_to_resume(self, resumed: ResumedMatch) -> None:
        match = resumed.match

        def take_it_up() -> None:
            self.match = match
            self._origin = self.clock() - resumed.at
            self.journal = resumed.journal
            self.keep_journal(resumed.accept)
            self._say(
                f"Resumed. {RECORD_WITH_ESC}"
                if match.phase is Phase.OVER
                else "Resumed, paused: Space starts the clocks when the cars are on the track."
            )
            self._draw()

        over = match.phase is Phase.OVER
        time_left = None if over else match.time_left(resumed.at)
        self.offer_to_resume(
            time_left,
            sum(len(heat.laps) for heat in match.cars),
            take_it_up,
            resumed.journal.forget,
        )

    # --- keys -------------------------------------------------------------------------

    def action_start_pause(self) -> None:
        self._input("start_or_pause")

    def action_capture(self, car: int) -> None:
        self._input("capture", car=car)

    def action_reset(self, car: int) -> None:
        self._input("reset", car=car)

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        """A click on a car's laps chooses that car, as Tab does."""
        name = event.widget.id or ""
        if name.startswith("mt-laps-") and int(name.rsplit("-", 1)[1]) != self.chosen:
            self._choose(int(name.rsplit("-", 1)[1]))

    def action_choose_car(self) -> None:
        self._choose((self.chosen + 1) % len(self.setup.cars))

    def action_undo_capture(self) -> None:
        self._input("undo_capture", car=self.chosen)

    def action_undo_reset(self) -> None:
        self._input("undo_reset", car=self.chosen)

    def action_retire(self) -> None:
        car = self.chosen
        if self.match.cars[car].phase is not Phase.RUNNING:
            self._input("retire", car=car)  # says why it cannot
            return
        moment = self.clock()

        def answered(yes: bool | None) -> None:
            if yes:
                self._input("retire", moment, car=car)

        self.ask_while_timing(
            f"Retire car {car + 1} ({self.setup.names[car]})?",
            "It is out of the race with the laps it completed; the lap in progress is not a "
            "lap. The other car races on.",
            answered,
            confirm_label="Retire",
            cancel_label="Keep racing",
        )

    def action_strike(self) -> None:
        car = self.chosen
        heat = self.match.cars[car]
        selected = self.query_one(f"#mt-laps-{car}", LapList).selected
        if not heat.laps or selected is None:
            self._say(f"Car {car + 1} has no lap captured yet.", error=True)
            return
        self._input("strike", car=car, lap=heat.laps[min(selected, len(heat.laps) - 1)].number)

    def action_end(self) -> None:
        phase = self.match.phase
        if phase is Phase.OVER:
            self._say(f"The race is over. {RECORD_WITH_ESC}")
            return
        if phase is Phase.READY:
            self._say("The race has not started; Space starts it.", error=True)
            return
        self.ask_to_end(
            self.clock(),
            lambda moment: self._input("end", moment),
            "The laps in progress do not count: each car's completed laps make the result.",
        )

    @property
    def unfinished_race(self) -> str:
        """What quitting now would leave unfinished ("" for nothing)."""
        if self.match.phase in (Phase.RUNNING, Phase.PAUSED):
            return "a physical match is being timed; its laps are kept, and r resumes it"
        return ""

    def action_leave(self) -> None:
        match = self.match
        if match.phase is Phase.OVER:
            result = match.result(self.setup.track, list(self.setup.cars))
            self.dismiss(result)
            return
        if match.phase is Phase.READY:
            self.dismiss(None)
            return

        self.ask_to_leave()

    # --- inputs -----------------------------------------------------------------------

    def _input(
        self, kind: str, now: float | None = None, *, car: int = 0, lap: int | None = None
    ) -> None:
        now = self.clock() if now is None else now
        if self._origin is None:
            self._origin = now
        at = now - self._origin
        was_over = self.match.phase is Phase.OVER
        try:
            said = take_match_input(self.match, kind, at, lap, car)
        except TimekeeperError as error:
            self._say(str(error), error=True)
        else:
            journal = self.journal
            if journal is not None:
                self.keep_journal(lambda: journal.took(kind, at, self.match, lap, car))
            if self.match.phase is Phase.OVER and not was_over:
                said = f"{said} {RECORD_WITH_ESC}"
            self._say(said)
        self._draw()

    # --- drawing ----------------------------------------------------------------------

    def _choose(self, car: int) -> None:
        self.chosen = car
        for k in range(len(self.setup.cars)):
            self.query_one(f"#mt-car-{k}").set_class(k == car, "-chosen")
        self.query_one(f"#mt-laps-{car}", LapList).focus()

    def _say(self, text: str, *, error: bool = False) -> None:
        self.said = Text(text, style="bold red" if error else "")
        self.query_one("#mt-said", Static).update(self.said)

    def _keys_text(self) -> Text:
        """Every key, in two lines that fit 60 columns: the race's keys, then those that act
        on the car Tab chose (wrapped text broke "f" from "retire" at 80)."""
        text = Text()
        for line, keys in enumerate(
            (
                (
                    ("1 2", "lap"),
                    ("q w", "reset"),
                    ("Space", "start/pause"),
                    ("e", "end"),
                    ("Esc", "record"),
                ),
                (
                    ("Tab", "car:"),
                    ("u", "undo lap"),
                    ("R", "undo reset"),
                    ("f", "retire"),
                    ("x", "strike"),
                ),
            )
        ):
            if line:
                text.append("\n")
            for key, what in keys:
                text.append(key, style="bold")
                text.append(f" {what}  ")
        return text

    def _now(self) -> float:
        return 0.0 if self._origin is None else self.clock() - self._origin

    def _draw_clocks(self) -> None:
        now = self._now()
        match = self.match
        left = countdown_text(match.time_left(now))
        digits = self.query_one("#mt-left", Digits)
        if digits.value != left:
            digits.update(left)
        for k in range(len(self.setup.cars)):
            # Ten times a second: a repaint only when what it says has changed (never
            # while the clocks stand still).
            facts = self._facts(k, now)
            if facts != self._facts_shown[k]:
                self._facts_shown[k] = facts
                self.query_one(f"#mt-facts-{k}", Static).update(facts)
        journal = self.journal
        if journal is not None and match.phase is Phase.RUNNING:
            self.keep_journal(lambda: journal.heartbeat(now))
        self._publish(now)

    def _publish(self, now: float) -> None:
        live = self.setup.live
        if live is None:
            return
        match = self.match
        order = match.running_order()
        leader = order[0]
        cars = [
            LiveCar(
                racer="",
                car="",
                place=order.index(k) + 1,
                laps=heat.laps_completed(),
                gap=None if k == leader else match.gap_seconds(leader, k),
                held_for="retired" if k in match.retired else "",
                finished=match.finished(k),
            )
            for k, heat in enumerate(match.cars)
        ]
        state = "over" if match.phase is Phase.OVER else "running"
        live.publish(state=state, clock=match.race_clock(now), cars=cars)

    def _draw(self) -> None:
        phase, style = {
            Phase.READY: ("Ready", "bold"),
            Phase.RUNNING: ("Running", "bold green"),
            Phase.PAUSED: ("Paused", "bold yellow"),
            Phase.OVER: ("Race over", "bold"),
        }[self.match.phase]
        state = Text(phase, style=style)
        order = self.match.running_order()
        if any(heat.laps for heat in self.match.cars):
            state.append("\nleading: ")
            state.append(self.setup.names[order[0]], style="bold")
        penalty = self.setup.rules.penalty_seconds
        state.append(
            f"\n{penalty:g} s added a reset" if penalty else "\nresets add no time", style="dim"
        )
        self.query_one("#mt-state", Static).update(state)
        for k, name in enumerate(self.setup.names):
            label = Text()
            label.append(f"{LAP_KEYS[k]} ", style="bold reverse")
            label.append(f" {name}", style=f"bold {car_colour(k)}")
            label.append(f"  {self.setup.cars[k].car}", style="dim")
            self.query_one(f"#mt-name-{k}", Static).update(label)
            self._fill_laps(k)
        self._draw_clocks()

    def _facts(self, k: int, now: float) -> Text:
        match, rules = self.match, self.setup.rules
        heat = match.cars[k]
        text = Text()
        if match.finished(k):
            text.append("Finished", style="bold green")
        elif heat.phase is Phase.OVER:
            why = "Retired" if k in match.retired else "Stopped" if match.ended else "Time up"
            text.append(why, style="bold")
        else:
            text.append(rules.lap_of(heat.laps_completed() + 1) if rules.lap_count else "Lap")
            text.append(f"  {lap_clock_text(heat.lap_clock(now))}", style="bold")
        limit = rules.max_offtracks_per_lap
        resets = f"\nresets {heat.resets}" + ("" if limit is None else f"/{limit}")
        text.append(resets, style="red" if limit is not None and heat.resets > limit else "")
        text.append(" this lap", style="dim")
        race_time = match.race_time(k)
        text.append("\nrace ")
        text.append(clock_text(race_time) if race_time is not None else "-", style="bold")
        order = match.running_order()
        gap = match.gap_seconds(order[0], k)
        if k != order[0] and gap is not None:
            text.append(f"  +{gap:.2f} s")
        return text

    def _fill_laps(self, k: int) -> None:
        heat = self.match.cars[k]
        flags = tuple(lap.struck for lap in heat.laps)
        shown = self._laps_shown[k]
        if flags == shown:
            return
        added = len(flags) > len(shown or ())
        lines = lap_lines(heat.lap_records(), heat.laps, self.setup.rules)
        self.query_one(f"#mt-laps-{k}", LapList).show(lines, select_last=added)
        self._laps_shown[k] = flags


def match_car(racer: str, car: str) -> MatchCar:
    """A physical car of a match, as the board names it."""
    return MatchCar(racer, car, car_hash(car))

"""The timekeeper: a physical car's heat timed by hand (or by an automatic timer's lap
triggers), with big clocks readable from a metre away.

The state machine is `league.timekeeper.heat.TimekeptHeat`; this screen feeds it keys and
timer lines with the moment each came and draws what it holds. Leaving a finished race
returns its result, which the Nights screen records like a simulated heat's.
"""

from __future__ import annotations

import hashlib
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Digits, Label, Static

from league.live_heat import LiveHeatWriter, live_laps
from league.timekeeper.feed import TIMER_ENV, FeedError, Trigger, follow, parse_trigger
from league.timekeeper.heat import Phase, TimekeeperError, TimekeptHeat, physical_floor
from league.timekeeper.journal import HeatJournal, Resumed, resume_heat, take_input
from racer_tui.app.screens.hand_timing import HandTimedScreen, lap_lines
from racer_tui.app.screens.race_screen import countdown_text
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.lap_list import LapList
from racer_tui.text.clocks import clock_text
from sim.foundation.plural import counted
from sim.race.result import RaceResult
from sim.race.rules import RaceRules, lap_counts
from sim.tracks.track import Track

CLOCK_HZ = 10.0
# Once the race is over: nothing is on the night until the timekeeper says so.
RECORD_WITH_ESC = "Esc records the heat on the night (strike a lap out first with x)."


@dataclass(frozen=True)
class TimekeeperSetup:
    track: Track
    rules: RaceRules
    racer: str
    car: str  # the car's name on the board
    title: str = ""
    timer: str | None = None  # an automatic timer's path, if the host gave one
    live: LiveHeatWriter | None = None  # a night's heat: where it is, for the projector
    journal: HeatJournal | None = None  # a night's heat: its inputs, to resume it


@dataclass
class TimerLine(Message):
    moment: float
    text: str


def lap_clock_text(seconds: float) -> str:
    """m:ss.t for the lap in progress (tenths: hundredths flicker unreadably)."""
    tenths = int(max(seconds, 0.0) * 10 + 1e-6)  # down, as a stopwatch shows; 4.2 stays 4.2
    minutes, rest = divmod(tenths, 600)
    return f"{minutes}:{rest // 10:02d}.{rest % 10}"


def car_hash(car: str) -> str:
    """A physical car's stand-in for a model's content hash: one per car name."""
    return "physical-" + hashlib.sha256(car.encode()).hexdigest()[:16]


class TimekeeperScreen(HandTimedScreen[RaceResult | None]):
    """Race time left and the lap in progress in big digits, the laps so far, and a key for
    everything the timekeeper does."""

    # Each key's tooltip is its line in the panel beside the laps, which shows every key:
    # the footer cannot hold them all at 80 columns, and a timekeeper must not hunt for
    # "did not finish" while a car is stuck.
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("space", "start_pause", "Start/pause", tooltip="start / pause", priority=True),
        Binding("l", "capture", "Lap", tooltip="capture lap / ⏎", priority=True),
        Binding("enter", "capture", "Lap", show=False, priority=True),
        Binding("r", "reset", "Reset", tooltip="car reset", priority=True),
        Binding("e", "end", "End race", tooltip="end the race"),
        Binding("R", "undo_reset", "Undo reset", tooltip="undo a reset", show=False),
        Binding("u", "undo_capture", "Undo lap", tooltip="undo a lap", show=False),
        Binding("f", "did_not_finish", "Not finished", tooltip="did not finish", show=False),
        Binding("x", "strike", "Strike lap", tooltip="strike a lap", show=False),
        Binding("escape", "leave", "Back", tooltip="record / back", show=False),
    ]
    TIMING_KEYS: ClassVar[dict[str, str]] = {"l": "capture", "r": "reset"}
    DEFAULT_CSS = """
    TimekeeperScreen #tk-title { text-style: bold; height: 1; }
    TimekeeperScreen #tk-clocks { height: 4; }
    TimekeeperScreen .tk-clock { width: 1fr; height: 4; }
    TimekeeperScreen #tk-facts { height: 1; }
    TimekeeperScreen #tk-said { height: auto; max-height: 3; }  /* whole at 60 columns */
    TimekeeperScreen #tk-body { height: 1fr; }
    TimekeeperScreen #tk-laps { width: 1fr; }
    TimekeeperScreen #tk-keys { width: 24; padding: 0 0 0 2; }
    """

    def __init__(self, setup: TimekeeperSetup) -> None:
        super().__init__()
        self.setup = setup
        # No lap under what a real car could drive is captured (the hull at a real car's
        # top speed): a double press mid-lap is said at once, not when the heat is recorded.
        self.floor_seconds = physical_floor(setup.track)
        self.heat = TimekeptHeat(setup.rules, floor_seconds=self.floor_seconds)
        self.clock: Callable[[], float] = time.monotonic  # a test may drive its own clock
        self.said = Text("Space starts the race when the car leaves the line.", style="dim")
        self._stop_feed = threading.Event()
        self._laps_shown: tuple[bool, ...] | None = None  # struck-out flags of the laps shown
        self.best_lap: float | None = None  # the best lap that counts so far
        # The heat runs on its own time: seconds since its first input (`_heat_time`), so
        # its journal replays it in another racer-tui exactly.
        self._origin: float | None = None
        self.journal = setup.journal

    def compose(self) -> ComposeResult:
        setup = self.setup
        title = setup.title or f"{setup.racer}, {setup.car}, on {setup.track.name}"
        yield Static(Text(title), id="tk-title")
        with Horizontal(id="tk-clocks"):
            with Vertical(classes="tk-clock"):
                yield Label("Time left")
                yield Digits(countdown_text(setup.rules.window_seconds), id="tk-left")
            with Vertical(classes="tk-clock"):
                yield Label("This lap")
                yield Digits(lap_clock_text(0.0), id="tk-lap")
        yield Static(id="tk-facts")
        yield Static(id="tk-said")
        with Horizontal(id="tk-body"):
            yield LapList(id="tk-laps")
            yield Static(self._keys(), id="tk-keys")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.set_interval(1.0 / CLOCK_HZ, self._draw_clocks)
        self._draw()
        timer = self.setup.timer if self.setup.timer is not None else os.environ.get(TIMER_ENV)
        if timer:
            self._follow_timer(timer)
        journal = self.journal
        if journal is not None:
            resumed = resume_heat(
                journal.path, journal.heat_id, self.setup.rules, floor_seconds=self.floor_seconds
            )
            if resumed is not None:
                self._offer_to_resume(resumed)

    def _offer_to_resume(self, resumed: Resumed) -> None:
        heat = resumed.heat

        def take_it_up() -> None:
            self.heat = heat
            self._origin = self.clock() - resumed.at
            self.journal = resumed.journal
            self.keep_journal(resumed.accept)
            self._say(
                f"Resumed. {RECORD_WITH_ESC}"
                if heat.phase is Phase.OVER
                else "Resumed, paused: Space starts the clocks when the car is on the track."
            )
            self._draw()

        over = heat.phase is Phase.OVER
        time_left = None if over else heat.time_left(resumed.at)
        self.offer_to_resume(time_left, len(heat.laps), take_it_up, resumed.journal.forget)

    def on_unmount(self) -> None:
        self._stop_feed.set()
        if self.journal is not None:
            self.journal.close()  # the file stays: the heat may be resumed
        if self.setup.live is not None:
            self.setup.live.clear()  # the heat is no longer running here

    # --- the timer's lines ------------------------------------------------------------

    @work(thread=True, exclusive=True, group="timer", exit_on_error=False)
    def _follow_timer(self, path: str) -> None:
        try:
            for moment, line in follow(path, self._stop_feed, self.clock):
                self.post_message(TimerLine(moment, line))
        except (FeedError, OSError) as error:
            text = str(error) if isinstance(error, FeedError) else f"The timer {path}: {error}"
            self.post_message(TimerLine(self.clock(), f"# {text}"))

    def on_timer_line(self, message: TimerLine) -> None:
        if message.text.startswith("# "):  # the feed itself failed: keys still work
            self._say(f"{message.text[2:]} Keys still time the race.", error=True)
            return
        try:
            trigger = parse_trigger(message.text)
        except FeedError as error:
            self._say(str(error), error=True)
            return
        if trigger is Trigger.LAP:
            self._input("timer_capture", message.moment)
        elif trigger is Trigger.RESET:
            self._input("reset", message.moment)

    # --- keys -------------------------------------------------------------------------

    def action_start_pause(self) -> None:
        self._input("start_or_pause")

    def action_capture(self) -> None:
        self._input("capture")

    def action_reset(self) -> None:
        self._input("reset")

    def action_undo_reset(self) -> None:
        self._input("undo_reset")

    def action_undo_capture(self) -> None:
        self._input("undo_capture")

    def action_did_not_finish(self) -> None:
        self._input("did_not_finish")

    def action_strike(self) -> None:
        selected = self.query_one(LapList).selected
        if not self.heat.laps or selected is None:
            self._say("No lap has been captured yet.", error=True)
            return
        captured = self.heat.laps[min(selected, len(self.heat.laps) - 1)]
        if not captured.finished:  # it never counts: striking it would change nothing
            self._say(
                f"Lap {captured.number} did not finish, so it never counts; nothing to strike.",
                error=True,
            )
            return
        self._input("strike", lap=captured.number)

    def action_end(self) -> None:
        if self.heat.phase is Phase.OVER:
            self._say(f"The race is over. {RECORD_WITH_ESC}")
            return
        if self.heat.phase is Phase.READY:
            self._say("The race has not started; Space starts it.", error=True)
            return
        self.ask_to_end(
            self.clock(),  # the race ends when e was pressed, not when answered
            lambda moment: self._input("end", moment),
            "The lap in progress does not count. The laps captured so far make the result.",
        )

    @property
    def unfinished_race(self) -> str:
        """What quitting now would leave unfinished ("" for nothing)."""
        if self.heat.phase in (Phase.RUNNING, Phase.PAUSED):
            return "a physical car's heat is being timed; its laps are kept, and r resumes it"
        return ""

    def action_leave(self) -> None:
        heat = self.heat
        if heat.phase is Phase.OVER:
            setup = self.setup
            self.dismiss(
                heat.result(
                    racer=setup.racer,
                    car=setup.car,
                    car_hash=car_hash(setup.car),
                    track_name=setup.track.name,
                    track_hash=setup.track.content_hash,
                )
            )
            return
        if heat.phase is Phase.READY:
            self.dismiss(None)
            return

        self.ask_to_leave()

    # --- drawing ----------------------------------------------------------------------

    def _heat_time(self, now: float) -> float:
        """`now` (this screen's clock) as the heat's own time."""
        return 0.0 if self._origin is None else now - self._origin

    def _input(self, kind: str, now: float | None = None, *, lap: int | None = None) -> None:
        """Give the heat one input, note it in the journal, and say what it did or why it
        could not."""
        now = self.clock() if now is None else now
        if self._origin is None:
            self._origin = now
        at = self._heat_time(now)
        was_over = self.heat.phase is Phase.OVER
        try:
            said = take_input(self.heat, kind, at, lap)
        except TimekeeperError as error:
            self._say(str(error), error=True)
        else:
            journal = self.journal
            if journal is not None:
                self.keep_journal(lambda: journal.took(kind, at, self.heat, lap))
            if self.heat.phase is Phase.OVER and not was_over:
                said = f"{said} {RECORD_WITH_ESC}"
            self._say(said)
        self._draw()

    def _say(self, text: str, *, error: bool = False) -> None:
        self.said = Text(text, style="bold red" if error else "")
        self._show_said()

    def _show_said(self) -> None:
        # A layout repaints every widget on the screen: only a sentence that changes its
        # height needs one, and most keys say a sentence.
        said = self.query_one("#tk-said", Static)
        lines = min(len(self.said.wrap(self.app.console, max(said.size.width, 1))), 2)
        said.update(self.said, layout=lines != said.size.height)

    def _draw_clocks(self) -> None:
        now = self._heat_time(self.clock())
        heat = self.heat
        # Digits repaints on every update: only a changed value is worth one (ten times a
        # second while the race runs, never while it stands still).
        for selector, value in (
            ("#tk-left", countdown_text(heat.time_left(now))),
            # Once the race is over no lap is running: its clock says so.
            (
                "#tk-lap",
                "-:--.-" if heat.phase is Phase.OVER else lap_clock_text(heat.lap_clock(now)),
            ),
        ):
            digits = self.query_one(selector, Digits)
            if digits.value != value:
                digits.update(value)
        journal = self.journal
        if journal is not None and heat.phase is Phase.RUNNING:
            self.keep_journal(lambda: journal.heartbeat(now))
        if self.setup.live is not None:
            self.setup.live.publish(
                state=heat.phase.value,
                time_left=heat.time_left(now),
                # In a lap-count race, the lap of the race (as the timekeeper's line says).
                lap=(
                    len(heat.laps) if self.setup.rules.lap_count is None else heat.laps_completed()
                )
                + (heat.phase is not Phase.OVER),
                lap_time=heat.lap_clock(now) if heat.phase is not Phase.OVER else 0.0,
                best_lap=self.best_lap,
                offtracks=heat.resets,
                limit=self.setup.rules.max_offtracks_per_lap,
                laps=live_laps(heat.lap_records()),
            )

    def _draw(self) -> None:
        self.best_lap = self._best()  # changes only with an input, never with the clock
        self._draw_clocks()
        self.query_one("#tk-facts", Static).update(self._facts(), layout=False)  # one line
        self._show_said()
        if tuple(lap.struck for lap in self.heat.laps) != self._laps_shown:
            self._fill_laps()

    def _keys(self) -> Text:
        text = Text()
        for binding in self.BINDINGS:
            if isinstance(binding, Binding) and binding.tooltip:
                key = "Esc" if binding.key == "escape" else binding.key
                text.append(f"{key:<6}", style="bold")
                text.append(f"{binding.tooltip}\n")
        return text

    def _facts(self) -> Text:
        heat, rules = self.heat, self.setup.rules
        limit = rules.max_offtracks_per_lap
        text = Text()
        phase = {
            Phase.READY: ("Ready", "bold"),
            Phase.RUNNING: ("Running", "bold green"),
            Phase.PAUSED: ("Paused", "bold yellow"),
            Phase.OVER: ("Race over", "bold"),
        }[heat.phase]
        text.append(phase[0], style=phase[1])
        if rules.lap_count is not None and heat.phase is not Phase.OVER:
            text.append(f"  {rules.lap_of(heat.laps_completed() + 1)}")
        over = limit is not None and heat.resets > limit
        resets = f"  Resets {heat.resets}" + ("" if limit is None else f"/{limit}")
        text.append(resets, style="red" if over else "")
        records = heat.lap_records()
        counting = sum(1 for lap in records if lap_counts(lap, rules))
        best = self.best_lap
        text.append("  Best ")
        text.append(clock_text(best) if best is not None else "-", style="bold")
        text.append(f"  {counting} of {counted(len(records), 'lap')} count")
        return text

    def _best(self) -> float | None:
        """The best lap that counts so far."""
        rules = self.setup.rules
        laps = self.heat.lap_records()
        return min((lap.time_seconds for lap in laps if lap_counts(lap, rules)), default=None)

    def _fill_laps(self) -> None:
        """Show the laps again: a new one is selected, a lap taken back or struck out keeps
        the selection where it was."""
        flags = tuple(lap.struck for lap in self.heat.laps)
        added = len(flags) > len(self._laps_shown or ())
        lines = lap_lines(self.heat.lap_records(), self.heat.laps, self.setup.rules)
        self.query_one(LapList).show(lines, select_last=added)
        self._laps_shown = flags

"""The head-to-head race view: two to six cars on one track, each in its own colour with
its racer's name, the running order with gaps in seconds, and crashes and overtakes as
they happen; live, and played again (r) once it is over.

The race runs in a thread worker as fast as the simulation allows
(`sim.race.head_to_head_ticks`); the view plays its ticks against the wall clock at 1x,
2x or 4x (`racer_tui.app.playback`), as the time trial's view does.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Digits, Static

from league.live_match import INCIDENTS_KEPT as INCIDENTS_SENT
from league.live_match import LiveCar, LiveIncident, LiveMatchWriter
from racer_tui.app.playback import PLAYBACK_BINDINGS, PlaybackClock, PlaybackKeys
from racer_tui.app.screens.base import RacerScreen, error_message
from racer_tui.app.screens.dialogs import ask
from racer_tui.app.screens.race_screen import FRAME_HZ, PANEL_HZ, countdown_text
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.race_map import RaceMap, RacingCar
from racer_tui.text.clocks import elapsed_text
from racer_tui.text.head_to_head import incident_sentence
from sim.race.head_to_head import Entry, HeadToHeadResult, Incident
from sim.race.head_to_head_ticks import HeadToHeadTick, head_to_head_ticks
from sim.race.rules import RaceRules
from sim.tracks.track import Track

# The cars' colours in grid order: deepracer-for-cloud's head-to-head cars are orange and
# purple; the rest are told apart from them and from each other on dark and light themes.
CAR_COLOURS = ("dark_orange", "medium_purple1", "deep_sky_blue1", "green3", "hot_pink", "gold1")
CAR_GLYPH = "■"
INCIDENTS_KEPT = 12  # the newest first: a short panel cuts the oldest
# What a car serving a penalty is held for, in the running order's gap column.
HELD_WORDS = {"crash": "crash", "off track": "off", "reversed": "turned"}


@dataclass(frozen=True)
class HeadToHeadSetup:
    """What to race: the cars' names in grid order and how to build their entries (in
    the view's worker: loading a model's policy takes a moment)."""

    track: Track
    rules: RaceRules
    names: tuple[str, ...]
    entries: Callable[[], Sequence[Entry]]
    seed: int = 0
    # A night's bracket match: where it is, for the night's projector. It is recorded when
    # the view is left after its finish, and is named ("Final (W2-1)").
    live: LiveMatchWriter | None = None
    match: str = ""


def car_colour(grid_index: int) -> str:
    """A car's colour, by its place on the grid: the same on the race view and the
    night's projector."""
    return CAR_COLOURS[grid_index % len(CAR_COLOURS)]


def car_labels(names: Sequence[str]) -> list[str]:
    """`#grid name` for each car: two cars of one model are told apart by their grid."""
    return [f"#{k + 1} {name}" for k, name in enumerate(names)]


def standings_text(tick: HeadToHeadTick, labels: Sequence[str], width: int) -> Text:
    """The running order, a line per car: position, colour, name, lap and gap to the
    leader (a car serving a penalty is dim and says so while the race runs; at the end
    every car has its gap)."""
    text = Text(no_wrap=True, overflow="ellipsis")
    name_width = max(width - 15, 6)  # "1 ■ ", " L12" and " " and a gap of six
    for place, k in enumerate(tick.order, start=1):
        car = tick.cars[k]
        if place > 1:
            text.append("\n")
        text.append(f"{place} ")
        text.append(CAR_GLYPH, style=f"bold {car_colour(k)}")
        name = labels[k]
        if len(name) > name_width:
            name = name[: name_width - 1] + "…"
        held = car.held > 0 and tick.result is None
        text.append(f" {name:<{name_width}}", style="dim" if held else "")
        text.append(f" {f'L{car.lap}':>3}")
        gap = tick.gaps[k]
        if held:
            text.append(f" {HELD_WORDS.get(car.held_for, 'held'):>6}", style="bold red")
        elif place == 1:
            text.append(f" {'✓' if car.finished else 'lead':>6}", style="bold")
        else:
            text.append(f" {gap_text(gap):>6}")
    return text


def gap_text(gap: float | None) -> str:
    """A gap to the leader in at most six characters: tenths below 100 s."""
    if gap is None:
        return "-"
    return f"+{gap:.1f}" if gap < 99.95 else f"+{gap:.0f}"


def incident_lines(incidents: Sequence[Incident], labels: Sequence[str]) -> Text:
    """Crashes and overtakes so far, newest first, each with its moment (m:ss)."""
    names = dict(enumerate(labels))
    text = Text()
    for n, incident in enumerate(reversed(incidents[-INCIDENTS_KEPT:])):
        if n:
            text.append("\n")
        clock = elapsed_text(incident.clock)
        style = "red" if incident.kind == "crash" else ""
        text.append(f"{clock} ", style="dim")
        text.append(incident_sentence(incident, names), style=style)
    return text


class HeadToHeadScreen(PlaybackKeys, RacerScreen[HeadToHeadResult | None]):
    """A head-to-head race, live, then played again as often as the racer likes."""

    BINDINGS = [  # noqa: RUF012 - Textual's convention
        *PLAYBACK_BINDINGS,
        Binding("r", "restart", "Replay"),
        Binding("escape", "leave", "Back"),
    ]
    DEFAULT_CSS = """
    HeadToHeadScreen #h2h-body { height: 1fr; }
    HeadToHeadScreen #h2h-map { width: 1fr; }
    HeadToHeadScreen #h2h-side { width: 36; padding: 0 1; }
    HeadToHeadScreen #h2h-title { text-style: bold; height: auto; max-height: 2; }
    HeadToHeadScreen #h2h-countdown { width: auto; }
    HeadToHeadScreen #h2h-facts { height: auto; }
    HeadToHeadScreen #h2h-order { height: auto; margin: 1 0 0 0; }
    HeadToHeadScreen #h2h-incidents { height: 1fr; margin: 1 0 0 0; }
    HeadToHeadScreen.-narrow #h2h-side { width: 30; }
    """
    NARROW = 76  # below this many columns the side panel narrows and the map keeps room

    def __init__(self, setup: HeadToHeadSetup) -> None:
        super().__init__()
        self.setup = setup
        self.labels = car_labels(setup.names)
        self.ticks: list[HeadToHeadTick] = []
        self.result: HeadToHeadResult | None = None
        self.failure: str | None = None
        self.clock = PlaybackClock()
        self.incidents: list[Incident] = []  # those up to the tick shown
        self._index = 0
        self._at_end_shown = False  # what the footer's space was last worked out for
        self.finish_shown = False  # the view has shown the race's end at least once
        self._last_panel = 0.0
        self.frames = 0

    def compose(self) -> ComposeResult:
        setup = self.setup
        with Horizontal(id="h2h-body"):
            yield RaceMap(setup.track, id="h2h-map")
            with Vertical(id="h2h-side"):
                yield Static(Text(self.title_words), id="h2h-title")
                yield Digits(countdown_text(setup.rules.window_seconds), id="h2h-countdown")
                yield Static(id="h2h-facts")
                yield Static(id="h2h-order")
                yield Static(id="h2h-incidents")
        yield RacerFooter()

    @property
    def title_words(self) -> str:
        laps = self.setup.rules.lap_count
        length = f"{laps} lap{'s' if laps != 1 else ''}" if laps is not None else "most laps"
        race = f"{self.setup.match}: head-to-head" if self.setup.match else "Head-to-head"
        return f"{race}, {length}, on {self.setup.track.name}"

    @property
    def records_on_leave(self) -> bool:
        """A night's match: leaving after its finish records it on the night."""
        return bool(self.setup.match)

    def on_mount(self) -> None:
        self.set_interval(1.0 / FRAME_HZ, self._frame)
        self._update_panel(force=True)
        self.call_after_refresh(self._run_race)

    def on_resize(self) -> None:
        self.set_class(self.size.width < self.NARROW, "-narrow")

    def on_unmount(self) -> None:
        # Freed now rather than with the removed screen's cycle, in a full collection's
        # pause a key could meet (racer_tui.app.long_running).
        self.ticks = []
        if self.setup.live is not None:
            self.setup.live.clear()  # the projector goes back to the night

    @work(thread=True, exclusive=True, group="head-to-head")
    def _run_race(self) -> None:
        setup = self.setup
        try:
            entries = setup.entries()
            for tick in head_to_head_ticks(setup.track, setup.rules, entries, seed=setup.seed):
                self.ticks.append(tick)  # list.append is atomic: the frame timer reads it
                if tick.result is not None:
                    self.result = tick.result
        except Exception as error:  # shown to the racer; the app keeps running
            self.failure = f"The race stopped. {error_message(error)}"

    # --- playback --------------------------------------------------------------------

    def _frame(self) -> None:
        if not self.ticks:
            self.clock.wait()
            self._update_panel()
            return
        for index in self.ticks_reached(self._index):
            self._index = index
            self.incidents.extend(self.ticks[index].incidents)
        tick = self.ticks[self._index]
        self.query_one(RaceMap).show(None, cars=tuple(self._racing(tick, k) for k in tick.order))
        self.frames += 1
        self._update_panel()
        self._publish(tick)
        if self.at_end != self._at_end_shown:  # space neither pauses nor resumes now
            self._at_end_shown = self.at_end
            self.finish_shown = self.finish_shown or self.at_end
            self.refresh_bindings()

    def _publish(self, tick: HeadToHeadTick) -> None:
        """Where the match is, for the night's projector: as it is raced, then its finish
        (replays stay on this screen)."""
        live = self.setup.live
        if live is None:
            return
        if self.finish_shown and not self.at_end:  # a replay: the projector keeps the finish
            shown = live.match
            live.publish(
                state="over", clock=shown.clock, cars=shown.cars, incidents=shown.incidents
            )
            return
        place = {k: position for position, k in enumerate(tick.order, start=1)}
        cars = [
            LiveCar(
                racer="",  # the writer keeps the names it was given
                car="",
                place=place[k],
                laps=car.laps_completed,
                gap=tick.gaps[k],
                held_for=car.held_for if car.held > 0 else "",
                finished=car.finished,
                at=(car.x, car.y),
                heading=car.heading,
            )
            for k, car in enumerate(tick.cars)
        ]
        incidents = [
            LiveIncident(one.clock, one.kind, one.car, one.other)
            for one in self.incidents[-INCIDENTS_SENT:]
        ]
        state = "over" if self.at_end else "running"
        live.publish(state=state, clock=tick.clock, cars=cars, incidents=incidents)

    @staticmethod
    def _racing(tick: HeadToHeadTick, k: int) -> RacingCar:
        car = tick.cars[k]
        return RacingCar(car.x, car.y, car.heading, car_colour(k), car.held > 0)

    @property
    def tick(self) -> HeadToHeadTick | None:
        """The tick the view shows now."""
        return self.ticks[self._index] if self.ticks else None

    @property
    def at_end(self) -> bool:
        """The view shows the race's last moment (r plays it again)."""
        return bool(self.ticks) and self._index == len(self.ticks) - 1 and self.result is not None

    @property
    def playback(self) -> str:
        return self.clock.words(at_end=self.at_end, finish_shown=self.finish_shown)

    def _update_panel(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._last_panel < 1.0 / PANEL_HZ:
            return
        self._last_panel = now
        tick = self.tick
        remaining = self.setup.rules.window_seconds - (tick.clock if tick else 0.0)
        self.query_one("#h2h-countdown", Digits).update(countdown_text(remaining))
        self.query_one("#h2h-facts", Static).update(self._facts(tick))
        order = self.query_one("#h2h-order", Static)
        width = order.size.width or 34
        order.update(standings_text(tick, self.labels, width) if tick else Text())
        self.query_one("#h2h-incidents", Static).update(incident_lines(self.incidents, self.labels))

    def _facts(self, tick: HeadToHeadTick | None) -> Text:
        if self.failure:
            return Text(f"{self.failure} Esc goes back.", style="bold red")
        if tick is None:
            return Text("Lining the cars up on the grid…", style="dim")
        text = Text()
        leader = tick.cars[tick.order[0]]
        laps = self.setup.rules.lap_count
        text.append(f"Lap {leader.lap}" + (f" of {laps}" if laps is not None else ""), style="bold")
        text.append(f"   {self.playback}")
        if self.at_end and self.result is not None:
            winner = self.result.winner
            text.append("\n")
            if laps is not None and winner.finished_at is None:  # nobody completed the laps
                text.append("Time ran out: most laps won.\n", style="yellow")
            text.append(f"{self.labels[winner.car]} won.\n", style="bold green")
            after = "Esc records it on the night, r replays." if self.records_on_leave else ""
            text.append(after or "r replays, Esc goes back.", style="dim")
        return text

    # --- actions ---------------------------------------------------------------------

    def action_restart(self) -> None:
        """Play the race again from the grid (the simulation is not run again)."""
        if not self.restart_playback():
            return
        self._index = 0
        self.incidents = []
        self._at_end_shown = False
        self.refresh_bindings()
        self._frame()

    @property
    def unfinished_race(self) -> str:
        """What quitting now would leave unfinished ("" for nothing)."""
        if self.records_on_leave and not self.failure and not self.finish_shown:
            return "a bracket match is being raced; it is not recorded, and r races it again"
        return ""

    def action_leave(self) -> None:
        if self.records_on_leave and not self.failure and not self.finish_shown:
            # The simulation may be over long before the room has seen it: a match is
            # recorded only once its finish was on screen, and leaving sooner is asked.
            ask(
                self.app,
                "Leave the match before its finish?",
                "It is not recorded, and r on the Nights screen races it again. To record "
                "it, keep watching, or press e to see its finish at once.",
                self._leave_answered,
                confirm_label="Leave unrecorded",
                cancel_label="Keep watching",
            )
            return
        self.dismiss(self.result if self.finish_shown else None)

    def _leave_answered(self, yes: bool | None) -> None:
        if yes:
            self.dismiss(None)

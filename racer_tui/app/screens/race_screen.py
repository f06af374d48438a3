"""The live race view: a time trial drawn as it happens, or a recorded one replayed.

The race itself runs in a thread worker as fast as the simulation allows and appends its
ticks to a list; the screen plays that list back against a wall clock at 1x, 2x or 4x.
Drawing is decoupled from simulation: a 30 Hz frame timer picks the tick for the current
race clock, moves the car on the map (which repaints only the rows that change) and
refreshes the side panel at a calmer rate.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import DataTable, Digits, Static

from league.live_heat import LiveHeatWriter, live_laps
from racer_tui.app.jobs import Job, JobState
from racer_tui.app.playback import PLAYBACK_BINDINGS, PlaybackClock, PlaybackKeys
from racer_tui.app.screens.base import RacerScreen, error_message
from racer_tui.app.screens.coach import CoachScreen
from racer_tui.app.screens.dialogs import ask
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.race_map import CarMarker, RaceMap
from racer_tui.app.widgets.table_fill import FittedTable
from racer_tui.text.clocks import clock_text
from sim.garage.coach_session import coach_race
from sim.physics.objects.settings import RaceType
from sim.race.driver import Driver
from sim.race.engine import RaceTick, race_ticks
from sim.race.replay import GhostLap, replay_ticks
from sim.race.result import RaceResult
from sim.race.rules import RaceRules
from sim.tracks.track import Track

FRAME_HZ = 30.0
PANEL_HZ = 10.0
TRAIL_SECONDS = 3.0


@dataclass(frozen=True)
class RaceSetup:
    """What to show: a race to run live (`driver`), or a recorded result to replay."""

    track: Track
    rules: RaceRules
    racer: str
    driver: Callable[[], Driver] | None = None  # built in the worker; None = reference driver
    seed: int = 0
    replay: RaceResult | None = None
    ghost: GhostLap | None = None
    leader_seconds: float | None = None  # the leaderboard leader's score, for the gap
    # Whose score the gap is to: a night's simulated leader may not be its leader (a
    # physical car's hand-timed lap leads on a board of its own), so it is named.
    leader_name: str = ""
    title: str = ""
    live: LiveHeatWriter | None = None  # a night's heat: where it is, for the projector
    # A night's heat: records its result on the night (blocking, in the view's worker),
    # once, when the view shows its finish: the host sees the heat end and the standings
    # update at the same moment. Raises what the league refuses.
    record: Callable[[RaceResult], None] | None = None


def race_title(setup: RaceSetup) -> str:
    """The view's title: who races where, and among what when it is not a time trial."""
    title = setup.title or f"{setup.racer} on {setup.track.name}"
    rules = setup.rules
    return title if rules.race_type is RaceType.TIME_TRIAL else f"{title} · {rules.race_words}"


def countdown_text(seconds: float) -> str:
    """m:ss for the window countdown (rounded up, so it shows 0:00 only at the end)."""
    whole = int(np.ceil(max(seconds, 0.0) - 1e-9))
    return f"{whole // 60}:{whole % 60:02d}"


# What a racer can do once the race is over or has failed, in the race view's own keys.
AFTER_THE_RACE = "r replays, Esc goes back."
AFTER_A_LAP = "r replays, o coaches its best lap, Esc goes back."
# A night's heat, once its finish is shown.
RECORDING = "Recording it on the night…"
RECORDED = "Recorded on the night."
LEAVE = "Esc goes back."


def race_job(setup: RaceSetup, tick: RaceTick | None, failure: str | None) -> Job:
    """The race as the app's one status model for long jobs (`racer_tui.app.jobs`), at the
    moment the view shows: starting, running on the race clock against its window
    (`done` and `total` in seconds), finished with its best lap, or failed with why and
    the key that leaves."""
    verb = "Replaying" if setup.replay is not None else "Racing"
    what = f"{verb} {setup.racer} on {setup.track.name}"
    window = setup.rules.window_seconds
    if failure:
        return Job(what, JobState.FAILED, outcome=failure, fix=LEAVE)
    if tick is None:
        return Job(what, JobState.RUNNING, total=window)
    if tick.result is None:
        return Job(what, JobState.RUNNING, done=tick.clock, total=window)
    best = tick.result.best_lap
    outcome = f"best lap {clock_text(best.time_seconds)}" if best is not None else "no lap counted"
    return Job(what, JobState.DONE, done=tick.clock, total=window, outcome=outcome)


class RaceScreen(PlaybackKeys, RacerScreen[RaceResult | None]):
    """A time trial, live or replayed, with its laps table and countdown."""

    BINDINGS = [  # noqa: RUF012 - Textual's convention
        *PLAYBACK_BINDINGS,
        Binding("g", "toggle_ghost", "Ghost"),
        Binding("r", "restart", "Replay"),
        Binding("o", "coach", "Coach", tooltip="Its best lap against the limit lap, by sector"),
        Binding("escape", "leave", "Back"),
    ]
    DEFAULT_CSS = """
    RaceScreen #race-body { height: 1fr; }
    RaceScreen #race-map { width: 1fr; }
    RaceScreen #race-side { width: 34; padding: 0 1; }
    RaceScreen #race-title { text-style: bold; height: auto; }
    RaceScreen #countdown { width: auto; }
    RaceScreen #race-facts { height: auto; }
    RaceScreen #laps { height: 1fr; }
    """

    def __init__(self, setup: RaceSetup) -> None:
        super().__init__()
        self.setup = setup
        self.ticks: list[RaceTick] = []
        self.result: RaceResult | None = None
        self.failure: str | None = None
        self.clock = PlaybackClock()
        self.show_ghost = setup.ghost is not None
        self._index = 0
        self._bindings_at_end = False  # what the footer's space was last worked out for
        self._offtrack_xy: list[tuple[float, float]] = []
        self._laps_shown = 0
        self._last_panel = 0.0
        self._over_on_air = False  # the projector was told the heat is over: it stays so
        # A night's heat: "" until its finish is shown, then recording, recorded or why not.
        self.recording = ""
        self.frames = 0

    def compose(self) -> ComposeResult:
        setup = self.setup
        with Horizontal(id="race-body"):
            yield RaceMap(setup.track, id="race-map")
            with Vertical(id="race-side"):
                yield Static(Text(race_title(setup)), id="race-title")
                yield Digits(countdown_text(setup.rules.window_seconds), id="countdown")
                yield Static(id="race-facts")
                yield FittedTable(id="laps", cursor_type="row", zebra_stripes=True)
        yield RacerFooter()

    def on_mount(self) -> None:
        table = self.query_one("#laps", DataTable)
        table.add_columns("Lap", "Time", "Pen", "Off", "OK")
        self.set_interval(1.0 / FRAME_HZ, self._frame)
        self._update_panel(force=True)
        # The race (or the replay's 3,600 ticks) is worked out in a thread once the screen
        # has been drawn: started earlier, it holds the GIL while the first frame is laid
        # out and the key that opened the view waits twice as long for its answer.
        self.call_after_refresh(self._run_race)

    @work(thread=True, exclusive=True, group="race")
    def _run_race(self) -> None:
        setup = self.setup
        if setup.replay is not None:
            self._load_replay(setup.replay)
            return
        try:
            driver = setup.driver() if setup.driver is not None else None
            stream = race_ticks(
                setup.track, setup.rules, driver, racer=setup.racer, seed=setup.seed
            )
            for tick in stream:
                self.ticks.append(tick)  # list.append is atomic: the frame timer reads it
                if tick.result is not None:
                    self.result = tick.result
        except Exception as error:  # shown to the racer; the app keeps running
            self.failure = f"The race stopped. {error_message(error)}"

    def _load_replay(self, replay: RaceResult) -> None:
        try:
            ticks = replay_ticks(replay, self.setup.track)
        except (ValueError, IndexError) as error:  # a trace from elsewhere that does not add up
            self.failure = f"This race cannot be replayed: its trace is damaged ({error})."
            return
        if not ticks:
            self.failure = (
                "This race has no trace here to replay: it was stored without one, or "
                "it is older than the races this session keeps (replay it from the "
                "league's recorded races if it was submitted)."
            )
        self.ticks = ticks  # one assignment: the frame timer sees no ticks or all of them
        self.result = replay

    # --- playback --------------------------------------------------------------------

    def _frame(self) -> None:
        if not self.ticks:
            self.clock.wait()
            self._update_panel()
            return
        for index in self.ticks_reached(self._index):
            self._index = index
            tick = self.ticks[index]
            if tick.offtrack and not self.ticks[index - 1].offtrack:
                self._offtrack_xy.append((tick.x, tick.y))
        self._draw(self.ticks[self._index])
        result = self.ticks[self._index].result
        if result is not None:
            if self.at_end != self._bindings_at_end:  # space neither pauses nor resumes now
                self._bindings_at_end = self.at_end
                self.refresh_bindings()
            self._record_heat(result)

    def _record_heat(self, result: RaceResult) -> None:
        """A night's heat goes on the night once its finish is on screen."""
        if self.setup.record is not None and not self.recording:
            self.recording = RECORDING
            self._update_panel(force=True)
            self._send_to_night(result)

    @work(thread=True, exclusive=True, group="race-record", exit_on_error=False)
    def _send_to_night(self, result: RaceResult) -> None:
        assert self.setup.record is not None
        try:
            self.setup.record(result)
        except Exception as error:  # said in the view; Esc leaves it unrecorded
            self.app.call_from_thread(self._recorded_as, f"Not recorded: {error_message(error)}")
            return
        self.app.call_from_thread(self._recorded_as, RECORDED)

    def _recorded_as(self, outcome: str) -> None:
        self.recording = outcome
        self._update_panel(force=True)

    def _draw(self, tick: RaceTick) -> None:
        first = max(0, self._index - int(TRAIL_SECONDS * 15))
        trail = np.array([(t.x, t.y) for t in self.ticks[first : self._index + 1]])
        ghost = self.setup.ghost
        ghost_xy = ghost.position(tick.lap_time) if ghost is not None and self.show_ghost else None
        self.query_one(RaceMap).show(
            CarMarker(tick.x, tick.y, tick.heading),
            trail=trail,
            ghost=ghost_xy,
            offtracks=np.array(self._offtrack_xy).reshape(-1, 2),
            objects=tick.objects,
            # A head-to-bot race's objects are bot cars, drawn pointing where they drive.
            objects_are_cars=self.setup.rules.race_type is RaceType.HEAD_TO_BOT,
        )
        self.frames += 1
        self._update_panel()

    def _update_panel(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._last_panel < 1.0 / PANEL_HZ:
            return
        self._last_panel = now
        tick = self.ticks[self._index] if self.ticks else None
        rules = self.setup.rules
        remaining = rules.window_seconds - (tick.clock if tick else 0.0)
        self.query_one("#countdown", Digits).update(countdown_text(remaining))
        self.query_one("#race-facts", Static).update(self._facts(tick))
        if tick is not None and len(tick.laps) != self._laps_shown:
            self._add_laps(tick)
        self._on_air(tick, remaining)

    def _on_air(self, tick: RaceTick | None, remaining: float) -> None:
        """Tell a night's projector where the heat is, as this view shows it. Once the
        finish has been shown the heat stays over, also while the racer replays it."""
        live = self.setup.live
        if live is None or self.failure:
            return
        if tick is not None and tick.result is not None:
            self._over_on_air = True
        if self._over_on_air and self.result is not None:
            best = self.result.best_lap
            live.publish(
                state="over",
                time_left=0.0,
                lap=len(self.result.laps),
                lap_time=0.0,
                best_lap=best.time_seconds if best is not None else None,
                offtracks=0,
                limit=self.setup.rules.max_offtracks_per_lap,
                laps=live_laps(self.result.laps),
            )
            return
        valid = [lap.time_seconds for lap in tick.laps if lap.valid] if tick else []
        live.publish(
            state="ready" if tick is None else "paused" if self.paused else "running",
            time_left=remaining,
            lap=tick.lap if tick else 1,
            lap_time=tick.lap_time if tick else 0.0,
            best_lap=min(valid, default=None),
            offtracks=tick.lap_offtracks if tick else 0,
            limit=self.setup.rules.max_offtracks_per_lap,
            laps=live_laps(tick.laps) if tick else (),
            car_at=(tick.x, tick.y) if tick else None,
        )

    def on_unmount(self) -> None:
        if self.setup.live is not None:
            self.setup.live.clear()  # the heat is no longer running here
        # A removed screen is garbage in a reference cycle, freed only by a full collection;
        # its 3,600 ticks let go now are freed at once, not in a pause a key could meet
        # (racer_tui.app.long_running).
        self.ticks = []

    @property
    def job(self) -> Job:
        """Where the race is, as the view shows it now."""
        return race_job(self.setup, self.ticks[self._index] if self.ticks else None, self.failure)

    def _facts(self, tick: RaceTick | None) -> Text:
        rules = self.setup.rules
        text = Text()
        job = race_job(self.setup, tick, self.failure)
        if job.state is JobState.FAILED:
            return Text(f"{job.outcome} {job.fix}", style="bold red")
        if tick is None:
            return Text("Starting the race…", style="dim")
        limit = "∞" if rules.max_offtracks_per_lap is None else str(rules.max_offtracks_per_lap)
        state = self.playback
        text.append(f"{rules.lap_of(tick.lap)}  ", style="bold")
        text.append(clock_text(tick.lap_time) + "\n")
        over = (
            rules.max_offtracks_per_lap is not None
            and tick.lap_offtracks > rules.max_offtracks_per_lap
        )
        if over:
            # Past the limit the lap is already lost: say so instead of "4/3".
            text.append(
                f"Off-tracks this lap {tick.lap_offtracks}, over {limit}: the lap won't count\n",
                style="red",
            )
        else:
            text.append(f"Off-tracks this lap {tick.lap_offtracks}/{limit}\n")
        if rules.race_type is not RaceType.TIME_TRIAL:
            text.append(f"Crashes this lap {tick.lap_crashes}\n")
        if tick.penalty_remaining > 0:
            text.append(f"Penalty hold {tick.penalty_remaining:.1f} s\n", style="bold red")
        text.append(f"Speed {tick.speed:.1f} m/s   {state}\n")
        valid = [lap for lap in tick.laps if lap.valid]
        best = min((lap.time_seconds for lap in valid), default=None)
        text.append("Best ")
        text.append(clock_text(best) if best is not None else "-", style="bold")
        leader = self.setup.leader_seconds
        if best is not None and leader is not None:
            gap = best - leader
            to = f" to {self.setup.leader_name}" if self.setup.leader_name else ""
            text.append(f"  gap {gap:+.3f}{to}", style="green" if gap <= 0 else "yellow")
        text.append("\n")
        if job.state is JobState.DONE:
            text.append("Finished. ", style="bold green")
            if self.recording in (RECORDING, RECORDED):
                text.append(f"{self.recording} ", style="green")
            elif self.recording:
                text.append(f"{self.recording} ", style="bold red")
            counted = tick.result is not None and tick.result.best_lap is not None
            text.append(AFTER_A_LAP if counted else AFTER_THE_RACE, style="dim")
        return text

    def _add_laps(self, tick: RaceTick) -> None:
        table = self.query_one("#laps", DataTable)
        for lap in tick.laps[self._laps_shown :]:
            table.add_row(
                str(lap.number),
                clock_text(lap.time_seconds),
                f"{lap.penalty_seconds:g}",
                str(lap.offtracks),
                "✓" if lap.valid else "✗",
            )
        self._laps_shown = len(tick.laps)
        table.move_cursor(row=self._laps_shown - 1)

    # --- actions ---------------------------------------------------------------------

    @property
    def paused(self) -> bool:
        return self.clock.paused

    @property
    def race_clock(self) -> float:
        return self.clock.race_clock

    @property
    def playback(self) -> str:
        """How the view plays the race now, as the panel says it."""
        return self.clock.words(at_end=self.at_end, finish_shown=self.finish_shown)

    @property
    def at_end(self) -> bool:
        """The view shows the race's last moment: nothing is left to play or pause (r
        plays it again)."""
        return (
            bool(self.ticks)
            and self._index == len(self.ticks) - 1
            and self.ticks[-1].result is not None
        )

    def action_toggle_ghost(self) -> None:
        if self.setup.ghost is None:
            self.notify("There is no ghost lap to compare with yet.", severity="warning")
            return
        self.show_ghost = not self.show_ghost

    @property
    def finish_shown(self) -> bool:
        """The view has shown the race's end (a replay has it from the start)."""
        return self.setup.replay is not None or (
            bool(self.ticks) and self.ticks[self._index].result is not None
        )

    def action_restart(self) -> None:
        """Play the race again from the start (the simulation is not run again)."""
        if not self.restart_playback():
            return
        self._index = 0
        self._offtrack_xy = []
        self._laps_shown = 0
        self.query_one("#laps", DataTable).clear()
        self._bindings_at_end = False
        self.refresh_bindings()

    def action_coach(self) -> None:
        """The Coach view on the race's fastest counted lap."""
        if self.failure:
            self.notify(f"{self.failure} There is no lap to coach.", markup=False)
            return
        result = self.result if self.finish_shown else None
        if result is None:
            self.notify(
                "The race has not finished yet: e shows its end, then o coaches its best lap.",
                severity="warning",
                markup=False,
            )
            return
        best = result.best_lap
        if best is None:
            self.notify("No lap of this race counted, so there is no lap to coach.", markup=False)
            return

        load = partial(coach_race, self.setup.track, result)
        self.app.push_screen(CoachScreen(self.setup.racer, f"lap {best.number}", load))

    @property
    def unfinished_race(self) -> str:
        """What quitting now would leave unfinished ("" for nothing)."""
        if self.setup.record is not None and not self.recording and not self.failure:
            return "a night's heat is being raced; it is not recorded, and r runs it again"
        return ""

    def action_leave(self) -> None:
        if self.recording == RECORDING:
            self.notify("The heat is being recorded; a moment.", markup=False)
            return
        if self.setup.record is not None and not self.recording and not self.failure:
            # A night's heat left before its finish is not recorded: asked, never silent.
            ask(
                self.app,
                "Leave the heat before its finish?",
                "It is not recorded, and r on the Nights screen runs it again. To record it, "
                "keep watching, or press e to see its finish at once.",
                self._leave_answered,
                confirm_label="Leave unrecorded",
                cancel_label="Keep watching",
            )
            return
        self.dismiss(self.result)

    def _leave_answered(self, yes: bool | None) -> None:
        if yes:
            self.dismiss(None)

"""The welcome screen's demo: the reference driver lapping a built-in track, on a loop.

No training needed: the race engine runs the reference driver (the no-learning driver at
the grip limit) in a thread worker and appends ticks as they come, so the car starts moving
within a fraction of a second; playback follows the wall clock at 1x and starts again when
the short race is over. `freeze(clock)` stops the loop on one moment, for screenshots.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.timer import Timer
from textual.widgets import Static
from textual.worker import Worker, WorkerState

from racer_tui.app.widgets.race_map import CarMarker, RaceMap
from sim.race.engine import RaceTick, race_ticks
from sim.race.rules import RaceRules
from sim.tracks.track import Track

DEMO_SECONDS = 45.0
FRAME_HZ = 20.0
TRAIL_TICKS = 45  # three seconds at 15 Hz


def lap_clock(seconds: float) -> str:
    minutes, rest = divmod(max(seconds, 0.0), 60.0)
    return f"{int(minutes)}:{rest:06.3f}"


class DemoRace(Vertical):
    """A looping reference-driver race on `track`, with a one-line caption."""

    DEFAULT_CSS = """
    DemoRace { height: 1fr; }
    DemoRace > RaceMap { height: 1fr; }
    DemoRace > #demo-caption {
        height: 2;
        color: $text-muted;
        text-wrap: nowrap;
        text-overflow: ellipsis;
    }
    """

    def __init__(
        self,
        track: Track,
        *,
        seconds: float = DEMO_SECONDS,
        clock: Callable[[], float] = time.monotonic,
        id: str | None = None,
    ) -> None:
        super().__init__(id=id)
        self.track = track
        self.rules = RaceRules(window_seconds=seconds)
        self.clock = clock
        self.ticks: list[RaceTick] = []
        self.frames = 0
        self.car: CarMarker | None = None
        self._started = 0.0
        self._timer: Timer | None = None
        self._shown: RaceTick | None = None

    def compose(self) -> ComposeResult:
        yield RaceMap(self.track)
        yield Static(id="demo-caption")

    def on_mount(self) -> None:
        self._started = self.clock()
        self._simulate()
        self._timer = self.set_interval(1.0 / FRAME_HZ, self._frame)

    @work(thread=True, exclusive=True, group="demo-race", exit_on_error=False)
    def _simulate(self) -> None:
        for tick in race_ticks(self.track, self.rules, racer="reference driver"):
            self.ticks.append(tick)  # list.append is atomic; the frame timer only reads

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        # A demo is decoration: if it fails, say so in its caption and carry on.
        if event.state is WorkerState.ERROR:
            self.query_one("#demo-caption", Static).update(
                Text(f"The demo race stopped: {event.worker.error}", style="red")
            )

    @property
    def finished(self) -> bool:
        return bool(self.ticks) and self.ticks[-1].finished

    def _frame(self) -> None:
        if not self.ticks or not self.screen.is_current:
            return  # covered by another screen (a dialog, the timekeeper): nothing to draw
        elapsed = self.clock() - self._started
        if self.finished:
            elapsed %= self.ticks[-1].clock
        self.show_at(elapsed)

    def freeze(self, clock: float) -> None:
        """Stop the loop and show the moment `clock` seconds into the race."""
        if self._timer is not None:
            self._timer.stop()
            self._timer = None
        self.show_at(clock)

    def show_at(self, clock: float) -> None:
        ticks = self.ticks
        if not ticks:
            return
        # Ticks are 1/15 s apart except around penalty holds: a search, not an index.
        index = int(np.searchsorted([t.clock for t in ticks], clock, side="right")) - 1
        index = min(max(index, 0), len(ticks) - 1)
        tick = ticks[index]
        first = max(0, index - TRAIL_TICKS)
        trail = np.array([(t.x, t.y) for t in ticks[first : index + 1]])
        self.car = CarMarker(tick.x, tick.y, tick.heading)
        self.query_one(RaceMap).show(self.car, trail=trail)
        self.frames += 1
        if tick is not self._shown:
            self._shown = tick
            self.query_one("#demo-caption", Static).update(self._caption(tick))

    def _caption(self, tick: RaceTick) -> Text:
        text = Text(no_wrap=True, overflow="ellipsis")
        text.append("reference driver", style="bold")
        text.append(f" on {self.track.name}\n")
        text.append(figures_line(tick, self.size.width or 80))
        return text


def figures_line(tick: RaceTick, width: int) -> str:
    """The lap, its clock, the speed and the best lap in the widest wording that fits
    `width`: the demo has about 40 columns at 80x24, and a figure cut in the middle
    ("best 0:06.3…") reads as another figure. The speed goes first, then the spacing,
    then all but the best lap."""
    lap, clock = f"lap {tick.lap}", lap_clock(tick.lap_time)
    speed = f"{tick.speed:.1f} m/s"
    best_time = min((lap.time_seconds for lap in tick.laps if lap.valid), default=None)
    best = f"best {lap_clock(best_time)}" if best_time is not None else ""
    wordings = (
        "  ".join(part for part in (lap, clock, speed, best) if part),
        " ".join(part for part in (lap, clock, speed, best) if part),
        "  ".join(part for part in (lap, clock, best) if part),
        " ".join(part for part in (lap, clock, best) if part),
        best or f"{lap} {clock}",  # a narrow demo: the one figure worth its room
    )
    return next((wording for wording in wordings if len(wording) <= width), wordings[-1])

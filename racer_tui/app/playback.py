"""Playing a race back: the race clock a live view shows, run against the wall clock at
1x, 2x or 4x, paused, or kept to the newest moment worked out (e: to the end), and the
keys that move it.

The race views (the time trial's and the head-to-head's) work their race out in a thread
as fast as the simulation allows and draw, on each frame, the tick of this clock."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from textual.app import App
from textual.binding import Binding, BindingType
from textual.notifications import SeverityLevel

from racer_tui.app.screens.dialogs import ask

SPEEDS = (1, 2, 4)


class PlaybackClock:
    """Where a view's playback is on the race clock, and how it moves."""

    def __init__(self, wall: Callable[[], float] = time.monotonic) -> None:
        self._wall = wall
        self.speed = 1
        self.paused = False
        # After e: the view keeps to the newest tick worked out until the finish (a slow
        # machine may still be working the race out), not back at the chosen speed.
        self.to_end = False
        self.race_clock = 0.0
        self._wall_mark = wall()
        self._clock_mark = 0.0

    def _rebase(self) -> None:
        self._wall_mark = self._wall()
        self._clock_mark = self.race_clock

    def wait(self) -> None:
        """Nothing to show yet: the race clock starts with the first tick shown."""
        self._wall_mark = self._wall()

    def advance(self, newest: float) -> float:
        """The race clock now (`newest`: the clock of the newest tick worked out)."""
        if self.to_end:
            self.race_clock = max(self.race_clock, newest)
            self._rebase()
        elif not self.paused:
            self.race_clock = self._clock_mark + (self._wall() - self._wall_mark) * self.speed
        return self.race_clock

    def toggle_pause(self) -> None:
        self._rebase()
        self.paused = not self.paused
        self.to_end = False

    def set_speed(self, speed: int) -> None:
        self._rebase()
        self.speed = speed if speed in SPEEDS else 1
        self.to_end = False

    def skip_to_end(self) -> None:
        self.to_end = True
        self.paused = False

    def restart(self) -> None:
        """From the start again, playing at the chosen speed."""
        self.race_clock = 0.0
        self._rebase()
        self.paused = False
        self.to_end = False

    def words(self, *, at_end: bool, finish_shown: bool) -> str:
        """How the view plays the race now, as its panel says it."""
        if at_end:
            return "finished"
        if self.to_end and not finish_shown:
            return "to the end"
        return "paused" if self.paused else f"{self.speed}x"


# The playback keys of every race view. Space pauses or resumes: the footer shows the one
# word that says what it does now (a binding whose check is False is hidden, and the key
# tries the other); at the end neither shows (there is nothing to pause; r plays it again).
PLAYBACK_BINDINGS: list[BindingType] = [
    Binding("space", "pause", "Pause"),
    Binding("space", "resume", "Resume"),
    Binding("1", "speed(1)", "1x"),
    Binding("2", "speed(2)", "2x"),
    Binding("4", "speed(4)", "4x"),
    Binding("e", "skip_to_end", "End", show=False),
]


class _Tick(Protocol):
    @property
    def clock(self) -> float: ...


class _PlaybackView(Protocol):
    clock: PlaybackClock

    @property
    def ticks(self) -> Sequence[_Tick]: ...

    @property
    def at_end(self) -> bool: ...

    @property
    def finish_shown(self) -> bool: ...

    @property
    def unfinished_race(self) -> str: ...

    @property
    def app(self) -> App[Any]: ...

    def refresh_bindings(self) -> None: ...

    def notify(
        self, message: str, *, severity: SeverityLevel = ..., markup: bool = ...
    ) -> None: ...

    def _frame(self) -> None: ...

    def _update_panel(self, force: bool = False) -> None: ...


class PlaybackKeys:
    """The actions of `PLAYBACK_BINDINGS`, for a race view (a Screen, after this class
    in its bases) with a `PlaybackClock` and the ticks it plays, that says whether it
    shows the race's last moment (`at_end`) and has shown it (`finish_shown`), and draws
    its frame (`_frame`) and its side panel."""

    def check_action(self: _PlaybackView, action: str, parameters: tuple[object, ...]) -> bool:
        if action == "pause":
            return not self.clock.paused and not self.at_end
        if action == "resume":
            return self.clock.paused and not self.at_end
        return True

    def ticks_reached(self: _PlaybackView, index: int) -> list[int]:
        """The ticks after `index` that the race clock has reached by now, in order (the
        view draws the last; each may have something to note on the way). Call it only
        once there are ticks."""
        race_clock = self.clock.advance(self.ticks[-1].clock)
        reached = []
        last = len(self.ticks) - 1
        while index < last and self.ticks[index + 1].clock <= race_clock:
            index += 1
            reached.append(index)
        return reached

    def restart_playback(self: _PlaybackView) -> bool:
        """Back to the start, if the view has shown the race's end (r); False, with the
        racer told why, if not."""
        if not self.finish_shown:
            self.notify(
                "The race has not finished yet: e shows its end, then r replays it.",
                severity="warning",
                markup=False,
            )
            return False
        self.clock.restart()
        return True

    def action_pause(self: _PlaybackView) -> None:
        PlaybackKeys._toggle_pause(self)

    def action_resume(self: _PlaybackView) -> None:
        PlaybackKeys._toggle_pause(self)

    def _toggle_pause(self: _PlaybackView) -> None:
        self.clock.toggle_pause()
        self._update_panel(force=True)
        self.refresh_bindings()

    def action_speed(self: _PlaybackView, speed: int) -> None:
        self.clock.set_speed(speed)
        self._update_panel(force=True)

    def action_skip_to_end(self: _PlaybackView) -> None:
        """Jump to the end of the race: to the newest tick worked out, and on with each new
        one until the finish, however long the simulation still takes (space or a speed key
        goes back to playing it). A race the room is watching (a night's heat, a bracket
        match) is asked first: one key would cut its show on every screen."""
        if not self.ticks or self.clock.to_end:
            return
        if self.unfinished_race and not self.finish_shown:
            ask(
                self.app,
                "Show the finish now?",
                "The race jumps to its finish here and on the venue's screens. Its result "
                "is the same; the room only misses the rest of the show.",
                lambda yes: PlaybackKeys._skip_to_end(self) if yes else None,
                confirm_label="Show the finish",
                cancel_label="Keep watching",
            )
            return
        PlaybackKeys._skip_to_end(self)

    def _skip_to_end(self: _PlaybackView) -> None:
        was_paused = self.clock.paused
        self.clock.skip_to_end()
        if was_paused:
            self.refresh_bindings()
        self._frame()
        self._update_panel(force=True)

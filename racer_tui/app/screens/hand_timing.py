"""What the two timekeepers share: a physical car's heat (`timekeeper`) and a bracket
match of two physical cars (`match_timekeeper`) each keep a journal of their inputs, offer
to resume a heat a stopped racer-tui left, ask before ending or leaving a race, and list
each car's laps the same way."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, ClassVar

from rich.text import Text
from textual import events

from league.timekeeper.heat import CapturedLap
from league.timekeeper.journal import HeatJournal
from racer_tui.app.screens.base import RacerScreen, ResultT
from racer_tui.app.screens.dialogs import ConfirmDialog, ask
from racer_tui.app.screens.race_screen import countdown_text
from racer_tui.text.clocks import clock_text
from sim.foundation.plural import counted
from sim.race.result import LapRecord
from sim.race.rules import RaceRules, lap_counts


class TimingQuestion(ConfirmDialog):
    """A question asked while cars are on the track: the lap and reset keys still time
    them under it (a car crossing the line while the host reads "End the race?" is still
    a lap), every other key answers the question as any question's do."""

    def __init__(
        self,
        timing: HandTimedScreen[Any],
        title: str,
        message: str,
        confirm_label: str,
        cancel_label: str,
    ) -> None:
        super().__init__(title, message, confirm_label, cancel_label)
        self.timing = timing

    async def on_key(self, event: events.Key) -> None:
        action = self.timing.TIMING_KEYS.get(event.key)
        if action is not None:
            event.stop()
            event.prevent_default()
            await self.timing.run_action(action)


class HandTimedScreen(RacerScreen[ResultT]):
    """A screen timing physical cars by hand, with its journal (None: none kept)."""

    RACE_WORD: ClassVar[str] = "heat"  # what the host times: "heat" or "match"
    # The keys that time a car (key: action), which work under this screen's questions.
    TIMING_KEYS: ClassVar[dict[str, str]] = {}
    journal: HeatJournal | None = None

    def ask_while_timing(
        self,
        title: str,
        message: str,
        answered: Callable[[bool | None], None],
        *,
        confirm_label: str,
        cancel_label: str = "Cancel",
    ) -> None:
        """Ask a yes-or-no question in a dialog under which the timing keys still work."""
        dialog = TimingQuestion(self, title, message, confirm_label, cancel_label)
        self.app.push_screen(dialog, answered)

    def keep_journal(self, write: Callable[[], None]) -> None:
        """Write to the journal; if the disk refuses, say so once and time on without it:
        a journal is a safety net, never a reason to stop a race."""
        try:
            write()
        except OSError as error:
            self.journal = None
            word = self.RACE_WORD
            self.notify(
                f"This {word}'s journal cannot be written ({error.strerror or error}): the "
                f"timing goes on, but if racer-tui stops, this {word} cannot be resumed.",
                severity="warning",
                markup=False,
            )

    def offer_to_resume(
        self,
        time_left: float | None,
        laps: int,
        resumed: Callable[[], None],
        forget: Callable[[], None],
    ) -> None:
        """Ask whether to resume the race a stopped racer-tui left, with `time_left`
        (None: its race was over) and `laps` captured: `resumed` takes it up, `forget`
        throws it away."""
        where = (
            "with its race over" if time_left is None else f"with {countdown_text(time_left)} left"
        )

        def answered(start_again: bool | None) -> None:
            if start_again:
                self.keep_journal(forget)
            else:  # Esc, n or Enter keep what was timed
                resumed()

        # Starting again throws the timed laps away, so it is the deliberate key (y), and
        # Esc, n or Enter resume (the host walk lost a heat's laps to an Esc).
        word = self.RACE_WORD
        ask(
            self.app,
            "Throw away what was timed and start again?",
            f"racer-tui stopped during this {word}, {where} and {counted(laps, 'lap')} "
            "captured. Resume it "
            "where it stopped, or start it again from the line, losing what was timed?",
            answered,
            confirm_label="Start again",
            cancel_label="Resume",
        )

    def ask_to_end(self, moment: float, end: Callable[[float], None], what_counts: str) -> None:
        """Ask before ending the race; it ends at `moment`, when the key was pressed."""

        def answered(yes: bool | None) -> None:
            if yes:
                end(moment)

        self.ask_while_timing("End the race?", what_counts, answered, confirm_label="End race")

    def ask_to_leave(self) -> None:
        """Leaving a race being timed records nothing: asked first."""

        def answered(yes: bool | None) -> None:
            if yes:
                journal = self.journal
                if journal is not None:
                    self.keep_journal(journal.forget)  # given up: nothing to resume
                self.dismiss(None)

        word = self.RACE_WORD
        self.ask_while_timing(
            f"Leave this {word}?",
            f"Its laps so far are thrown away: nothing is recorded, and r times the {word} "
            "again from the line.",
            answered,
            confirm_label="Leave unrecorded",
            cancel_label="Keep timing",
        )


def lap_lines(
    records: Sequence[LapRecord], laps: Sequence[CapturedLap], rules: RaceRules
) -> list[tuple[tuple[str, ...], Text]]:
    """A car's laps as a `LapList` shows them: number, time, raw time, resets, verdict."""
    lines: list[tuple[tuple[str, ...], Text]] = []
    for lap, captured in zip(records, laps, strict=True):
        # One short word each: the column is 6 wide at 60 columns, where a longer one
        # wrapped onto a line that looked like another lap.
        if not captured.finished:
            verdict = Text("DNF", style="red")
        elif captured.struck:
            verdict = Text("struck", style="red")
        elif lap_counts(lap, rules):
            verdict = Text("✓", style="green")
        else:
            verdict = Text("✗ resets", style="red")
        cells = (
            str(lap.number),
            clock_text(lap.time_seconds),
            clock_text(lap.raw_seconds),
            str(lap.offtracks),
        )
        lines.append((cells, verdict))
    return lines

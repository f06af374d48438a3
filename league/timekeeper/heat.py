"""One physical car's heat as the timekeeper runs it: a state machine fed with key presses
(or an automatic timer's lines) and the time they came, never reading a clock itself, so
the app, a timer feed and the tests drive it alike.

Phases: READY (the car is on the line) -> RUNNING <-> PAUSED -> OVER. Both clocks, the
race's and the lap's, run only while RUNNING. The race clock counts the rules' window down;
when it reaches zero the race goes on until the lap in progress is captured (or the car did
not finish it, or the timekeeper ends the race), as at DeepRacer's physical events. A
lap-count race is over at the capture of its last lap, or when time is up as above.

A lap's resets are its off-tracks: more than the rules' limit and the lap does not count,
and each adds the rules' `penalty_seconds` to the lap's time (a league that counts only the
time lost putting the car back sets it to 0). Raw and penalised times are both kept.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

from sim.coach.plausible import fastest_possible_lap
from sim.foundation.ids import new_id
from sim.foundation.remedies import RemedyError
from sim.physics.labels import PHYSICAL
from sim.race.result import LapRecord, RaceResult, now_iso
from sim.race.rules import RaceRules, lap_counts, score_laps
from sim.tracks.track import Track

# A capture this soon after the lap started is a double press or a timer's bounce, not a
# lap: no DeepRacer track is driven in under a second.
MIN_LAP_SECONDS = 1.0


def physical_floor(track: Track) -> float:
    """Seconds no real car's lap of `track` is under: its shortest loop at a real car's top
    speed (`sim.coach.plausible.PHYSICAL_TOP_SPEED`, which says why it is so generous), the
    floor a physical heat's result is checked against when it is recorded."""
    return fastest_possible_lap(track, PHYSICAL)


class Phase(StrEnum):
    READY = "ready"
    RUNNING = "running"
    PAUSED = "paused"
    OVER = "over"


class TimekeeperError(RemedyError):
    """An input that the heat's phase does not allow; the message says what to do."""


@dataclass(frozen=True)
class CapturedLap:
    number: int  # 1-based
    raw_seconds: float  # as captured, without penalties
    resets: int
    started_at: float  # race clock at the lap's start
    finished: bool = True  # False: the car did not finish it (it never counts)
    struck: bool = False  # the timekeeper struck it out (a lap that was not a lap)


class TimekeptHeat:
    """The heat's state. Every input takes `now`, seconds on a monotonic clock."""

    def __init__(self, rules: RaceRules, *, floor_seconds: float | None = None) -> None:
        self.rules = rules
        # No lap under this is a lap a real car drove (`physical_floor`): a capture before
        # it is a false finish, refused as a double press is.
        self.floor_seconds = floor_seconds
        self.phase = Phase.READY
        self.laps: list[CapturedLap] = []
        self.resets = 0  # in the lap in progress
        self.started_at = ""  # wall time of the start, ISO-8601, once started
        self._clock = 0.0  # race clock banked before the current run of RUNNING
        self._since: float | None = None  # `now` when RUNNING began, while it runs
        self._lap_start = 0.0  # race clock at the start of the lap in progress
        self._ended_on_laps = False  # a lap-count race ended by its last lap

    # --- clocks --------------------------------------------------------------------------

    def race_clock(self, now: float) -> float:
        """Seconds the race has run, past the window too."""
        return self._clock + (now - self._since if self._since is not None else 0.0)

    def time_left(self, now: float) -> float:
        return max(self.rules.window_seconds - self.race_clock(now), 0.0)

    def expired(self, now: float) -> bool:
        return self.race_clock(now) >= self.rules.window_seconds

    def lap_clock(self, now: float) -> float:
        """Seconds into the lap in progress."""
        return self.race_clock(now) - self._lap_start

    # --- inputs ---------------------------------------------------------------------------

    def start_or_pause(self, now: float) -> str:
        if self.phase is Phase.READY or self.phase is Phase.PAUSED:
            return self._run(now)
        if self.phase is Phase.RUNNING:
            self._halt(now)
            self.phase = Phase.PAUSED
            return "Paused: both clocks are stopped."
        raise TimekeeperError("The race is over; it cannot be started again.")

    def capture(self, now: float, *, from_timer: bool = False) -> str:
        """A lap is finished (Capture Lap, or the timer's line). From the timer, the car
        crossing the line starts a race that is ready and resumes a paused one."""
        if from_timer and self.phase in (Phase.READY, Phase.PAUSED):
            return self._run(now)
        self._require_running("capture a lap")
        seconds = self.lap_clock(now)
        if seconds < MIN_LAP_SECONDS:
            raise TimekeeperError(
                f"A lap of {seconds:.2f} s is a double press, not a lap; it was not captured."
            )
        if self.floor_seconds is not None and seconds < self.floor_seconds:
            raise TimekeeperError(
                f"A lap of {seconds:.2f} s is faster than a real car can drive this track "
                f"(no lap under {self.floor_seconds:.2f} s), so it was not captured; "
                "capture when the car crosses the line."
            )
        lap = self._close_lap(now, finished=True)
        return self._after_lap(now, lap)

    def reset(self, now: float) -> str:
        self._require_running("count a car reset")
        self.resets += 1
        limit = self.rules.max_offtracks_per_lap
        if limit is not None and self.resets > limit:
            return f"Reset {self.resets}: over {limit}, this lap will not count."
        return f"Reset {self.resets} this lap."

    def undo_reset(self) -> str:
        if self.phase is Phase.OVER or self.phase is Phase.READY:
            raise TimekeeperError("There is no lap in progress to take a reset from.")
        if self.resets == 0:
            raise TimekeeperError("This lap has no reset to undo.")
        self.resets -= 1
        return f"Reset taken back: {self.resets} this lap."

    def undo_capture(self, now: float) -> str:
        """The last capture was a false finish: its lap goes on, with its resets. A false
        finish that ended the race (time was up, or its last lap) reopens it, paused."""
        if not self.laps:
            raise TimekeeperError("No lap has been captured yet.")
        lap = self.laps.pop()
        self._lap_start = lap.started_at
        self.resets += lap.resets
        if self.phase is Phase.OVER:
            self.phase = Phase.PAUSED
            self._ended_on_laps = False
            return f"Lap {lap.number} taken back: the race is open again, paused."
        return f"Lap {lap.number} taken back: it goes on ({self._clock_text(now)})."

    def did_not_finish(self, now: float) -> str:
        """The car cannot finish the lap in progress: it is kept as a lap that does not
        count, and the clocks stop until the car is back on the line."""
        self._require_running("mark a lap not finished")
        lap = self._close_lap(now, finished=False)
        if self.phase is not Phase.OVER and not self.expired(now):
            self._halt(now)
            self.phase = Phase.PAUSED
            return f"Lap {lap.number} not finished; paused until the car is back on the line."
        return self._after_lap(now, lap)

    def strike(self, number: int, now: float) -> str:
        """Strike a captured lap out, or put it back (a lap that was not a lap). In a
        lap-count race that decides how many laps the car still owes."""
        index = next((i for i, lap in enumerate(self.laps) if lap.number == number), None)
        if index is None:
            raise TimekeeperError(f"There is no lap {number} to strike out.")
        lap = self.laps[index]
        count = self.rules.lap_count
        owed = count is not None and lap.struck and lap.finished
        if owed and count is not None and self.laps_completed() >= count:
            raise TimekeeperError(
                f"Lap {number} cannot count again: the race already has its {count} laps. "
                "Take a later lap back first (u)."
            )
        self.laps[index] = replace(lap, struck=not lap.struck)
        said = f"Lap {number} {'struck out' if not lap.struck else 'counts again'}."
        if count is None:
            return said
        done = self.laps_completed()
        if done >= count and self.phase in (Phase.RUNNING, Phase.PAUSED):
            self._halt(now)
            self.phase = Phase.OVER
            self._ended_on_laps = True
            return f"{said} {count} laps done: race over."
        reopen = done < count and self.phase is Phase.OVER and self._ended_on_laps
        if reopen and not self.expired(now):  # the car is owed a lap: it drives it
            self.phase = Phase.PAUSED
            self._ended_on_laps = False
            return f"{said} The race is open again, paused: {count - done} more to drive."
        return said

    def end(self, now: float) -> str:
        """End the race now; the lap in progress is not a lap."""
        if self.phase is Phase.READY:
            raise TimekeeperError("The race has not started; start it before ending it.")
        if self.phase is Phase.OVER:
            raise TimekeeperError("The race is already over.")
        self._halt(now)
        self.phase = Phase.OVER
        return "Race over."

    def run_on(self, now: float, clock: float, *, running: bool = True) -> None:
        """Stopped at race clock `clock`, or running from it (`running`): in a match, a car
        whose false finish (taken back) or struck lap stopped its clocks while the other
        cars raced on drove on all the while."""
        if self.phase is not Phase.PAUSED:
            raise TimekeeperError("Only a stopped car can run on.")
        self._clock = clock
        self._since = now if running else None
        self.phase = Phase.RUNNING if running else Phase.PAUSED

    # --- what it adds up to ---------------------------------------------------------------

    def laps_completed(self) -> int:
        """Laps the car finished, counting or not, for a lap-count race's end: a lap it did
        not finish or the timekeeper struck out was not driven."""
        return sum(1 for lap in self.laps if lap.finished and not lap.struck)

    def lap_records(self) -> tuple[LapRecord, ...]:
        records = []
        limit = self.rules.max_offtracks_per_lap
        for lap in self.laps:
            penalty = lap.resets * self.rules.penalty_seconds
            within = limit is None or lap.resets <= limit
            valid = lap.finished and not lap.struck and within
            records.append(
                LapRecord(
                    number=lap.number,
                    time_seconds=round(lap.raw_seconds + penalty, 3),
                    raw_seconds=round(lap.raw_seconds, 3),
                    penalty_seconds=penalty,
                    offtracks=lap.resets,
                    valid=valid,
                    started_at=round(lap.started_at, 3),
                )
            )
        return tuple(records)

    def result(
        self, *, racer: str, car: str, car_hash: str, track_name: str, track_hash: str
    ) -> RaceResult:
        """The heat as a league result, timed on a physical track (`sim.physics.labels`)."""
        if self.phase is not Phase.OVER:
            raise TimekeeperError("The race is still on; end it first.")
        laps = self.lap_records()
        return RaceResult(
            result_id=new_id(),
            racer=racer,
            model_name=car,
            model_hash=car_hash,
            track_name=track_name,
            track_hash=track_hash,
            rules=self.rules,
            seed=0,
            laps=laps,
            scoring=score_laps(laps, self.rules),
            total_offtracks=sum(lap.resets for lap in self.laps) + self.resets,
            started_at=self.started_at or now_iso(),
            physics=PHYSICAL,
        )

    # --- inside ---------------------------------------------------------------------------

    def _run(self, now: float) -> str:
        first = self.phase is Phase.READY
        if first:
            self.started_at = now_iso()
        self._since = now
        self.phase = Phase.RUNNING
        return "Race started." if first else "Running again."

    def _halt(self, now: float) -> None:
        self._clock = self.race_clock(now)
        self._since = None

    def _require_running(self, doing: str) -> None:
        if self.phase is Phase.RUNNING:
            return
        hint = {
            Phase.READY: "start the race first",
            Phase.PAUSED: "the race is paused; start it again first",
            Phase.OVER: "the race is over",
        }[self.phase]
        raise TimekeeperError(f"Cannot {doing}: {hint}.")

    def _close_lap(self, now: float, *, finished: bool) -> CapturedLap:
        clock = self.race_clock(now)
        lap = CapturedLap(
            number=len(self.laps) + 1,
            raw_seconds=clock - self._lap_start,
            resets=self.resets,
            started_at=self._lap_start,
            finished=finished,
        )
        self.laps.append(lap)
        self._lap_start = clock
        self.resets = 0
        return lap

    def _after_lap(self, now: float, lap: CapturedLap) -> str:
        record = self.lap_records()[-1]
        verdict = "counts" if lap_counts(record, self.rules) else "does not count"
        said = f"Lap {lap.number}: {record.time_seconds:.3f} s, {verdict}."
        if not lap.finished:
            said = f"Lap {lap.number} not finished."
        if self.rules.lap_count is not None and self.laps_completed() >= self.rules.lap_count:
            self._halt(now)
            self.phase = Phase.OVER
            self._ended_on_laps = True
            said += f" {self.rules.lap_count} laps done: race over."
        elif self.expired(now):  # the lap in progress at zero was the last
            self._halt(now)
            self.phase = Phase.OVER
            said += " Time is up: race over."
        return said

    def _clock_text(self, now: float) -> str:
        return f"{self.lap_clock(now):.1f} s into it"

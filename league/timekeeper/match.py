"""A bracket match between physical cars, timed by hand: two cars on one real track, one
race clock, each car's laps and resets its own (a lap key per car).

Each car is a `TimekeptHeat` fed the same moments, so its laps, resets, undo and strike
behave exactly as in a one-car heat; the match starts, pauses and ends them together.

Where a physical match departs from a simulated one (sim.race.head_to_head), and why:
- **Penalties are added to the time**, as a physical heat's are: no host can hold a real
  car for exactly the rules' 2 s after putting it back. A car's race time is the clock at
  its last lap's capture plus its resets' penalties.
- **Every car drives its laps.** A simulated race ends when the first car completes its
  last lap; here one car's penalties can still lose it the race after it crossed first,
  so the match goes on until every car has completed the race's laps, retired (`f`), or
  the timekeeper ends it. Time up ends each car at its next capture, as in a heat.
- **The order:** cars that completed the race's laps by race time; then the others by laps
  completed, then by the race time of their last lap. In a race for the window (no lap
  count): most laps, then the best lap, as in a simulated race. A car that retires
  forfeits: it is behind every car that did not.
- **No incidents:** the host times laps and resets; who touched whom is not recorded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from league.timekeeper.heat import Phase, TimekeeperError, TimekeptHeat
from sim.foundation.ids import new_id
from sim.race.head_to_head import MAX_CARS, MIN_CARS, CarFinish, HeadToHeadResult
from sim.race.result import RaceResult, now_iso
from sim.race.rules import RaceRules
from sim.tracks.track import Track

_RACING = (Phase.RUNNING, Phase.PAUSED)  # a car still in the race, running or paused


@dataclass(frozen=True)
class MatchCar:
    """One car of a physical match as the board names it."""

    racer: str
    car: str  # the car's name on the board ("physical car", or its own)
    car_hash: str  # the stand-in for a model's content hash, one per car name


class TimekeptMatch:
    """The match's state. Every input takes `now`, seconds on a monotonic clock, and the
    grid index of the car it is about (where it is about one car)."""

    def __init__(
        self, rules: RaceRules, cars: int = 2, *, floor_seconds: float | None = None
    ) -> None:
        if not MIN_CARS <= cars <= MAX_CARS:
            raise TimekeeperError(f"a match has {MIN_CARS} to {MAX_CARS} cars, not {cars}.")
        self.rules = rules
        self.cars = [TimekeptHeat(rules, floor_seconds=floor_seconds) for _ in range(cars)]
        self.ended = False  # the timekeeper ended it (e)
        self.retired: set[int] = set()  # cars out of the race (f)
        self.started_at = ""

    @property
    def floor_seconds(self) -> float | None:
        return self.cars[0].floor_seconds

    @floor_seconds.setter
    def floor_seconds(self, seconds: float | None) -> None:
        for heat in self.cars:
            heat.floor_seconds = seconds

    # --- the match's phase -----------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        if self.ended or all(heat.phase is Phase.OVER for heat in self.cars):
            return Phase.OVER
        phases = {heat.phase for heat in self.cars}
        if phases == {Phase.READY}:
            return Phase.READY
        return Phase.RUNNING if Phase.RUNNING in phases else Phase.PAUSED

    def race_clock(self, now: float) -> float:
        """Seconds the match has run: its longest-running car's (a car that is over has
        stopped its own clock)."""
        return max(heat.race_clock(now) for heat in self.cars)

    def time_left(self, now: float) -> float:
        return max(self.rules.window_seconds - self.race_clock(now), 0.0)

    # --- inputs ----------------------------------------------------------------------------

    def start_or_pause(self, now: float) -> str:
        """Start the clocks, pause them, or start them again: every car still racing."""
        phase = self.phase
        if phase is Phase.OVER:
            raise TimekeeperError("The race is over; it cannot be started again.")
        for heat in self.cars:
            if heat.phase is not Phase.OVER and (heat.phase is Phase.RUNNING) == (
                phase is Phase.RUNNING
            ):
                heat.start_or_pause(now)
        if phase is Phase.READY:
            self.started_at = self.cars[0].started_at
            return "Race started."
        return "Paused: the clocks are stopped." if phase is Phase.RUNNING else "Running again."

    def capture(self, car: int, now: float) -> str:
        return self._input(car, now, lambda heat: heat.capture(now))

    def reset(self, car: int, now: float) -> str:
        return self._input(car, now, lambda heat: heat.reset(now))

    def undo_reset(self, car: int, now: float) -> str:
        return self._input(car, now, lambda heat: heat.undo_reset())

    def undo_capture(self, car: int, now: float) -> str:
        """The car's last capture was a false finish: its lap goes on (a match that this
        capture ended is open again, paused). A retired car's laps stand."""
        if car in self.retired:
            raise TimekeeperError(f"Car {car + 1} is retired: its completed laps stand.")
        return self._input(car, now, lambda heat: heat.undo_capture(now))

    def retire(self, car: int, now: float) -> str:
        """The car cannot go on (f): it is out of the race with the laps it completed; the
        lap in progress is not a lap. The others race on."""

        def out(heat: TimekeptHeat) -> str:
            if heat.phase is Phase.OVER:
                raise TimekeeperError("Its race is over already.")
            heat.end(now)
            self.retired.add(car)
            return "retired: its completed laps stand."

        return self._input(car, now, out)

    def strike(self, car: int, lap: int, now: float) -> str:
        """Strike a captured lap out, or put it back (as in a heat), also once the race is
        ended: the result is what the timekeeper records."""
        return self._input(car, now, lambda heat: heat.strike(lap, now), once_ended=True)

    def end(self, now: float) -> str:
        """End the race now for every car; their laps in progress are not laps."""
        phase = self.phase
        if phase is Phase.READY:
            raise TimekeeperError("The race has not started; start it before ending it.")
        if phase is Phase.OVER:
            raise TimekeeperError("The race is already over.")
        for heat in self.cars:
            if heat.phase is not Phase.OVER:
                heat.end(now)
        self.ended = True
        return "Race over."

    # --- what it adds up to ----------------------------------------------------------------

    def race_time(self, car: int) -> float | None:
        """The car's race time at its last completed lap: the capture's clock plus the
        penalties of its laps so far; None before its first lap."""
        times = self._lap_times(car)
        return times[-1] if times else None

    def finished(self, car: int) -> bool:
        count = self.rules.lap_count
        return count is not None and self.cars[car].laps_completed() >= count

    def running_order(self) -> list[int]:
        """The cars' grid indexes, leader first (see the module's docstring); a retired car
        forfeits: it is behind every car that did not retire."""

        def key(k: int) -> tuple[float, ...]:
            heat = self.cars[k]
            retired = 1 if k in self.retired else 0
            time = self.race_time(k)
            time_key = time if time is not None else float("inf")
            if self.rules.lap_count is None:
                best = min(
                    (lap.time_seconds for lap in heat.lap_records() if lap.valid),
                    default=float("inf"),
                )
                return (retired, -heat.laps_completed(), best, k)
            return (retired, 0 if self.finished(k) else 1, -heat.laps_completed(), time_key, k)

        return sorted(range(len(self.cars)), key=key)

    def gap_seconds(self, leader: int, car: int) -> float | None:
        """How long after the leader the car completed its latest lap (their race times at
        that lap); None for a car with no lap, one the leader did not complete, or one it
        completed first (the leader has passed it since: how far behind is not timed)."""
        if car == leader:
            return 0.0
        theirs, leaders = self._lap_times(car), self._lap_times(leader)
        if not theirs or len(leaders) < len(theirs):
            return None
        gap = round(theirs[-1] - leaders[len(theirs) - 1], 3)
        return gap if gap >= 0.0 else None

    def result(self, track: Track, cars: list[MatchCar]) -> HeadToHeadResult:
        """The match as a head-to-head result, timed on a physical track."""
        if self.phase is not Phase.OVER:
            raise TimekeeperError("The race is still on; end it first.")
        if len(cars) != len(self.cars):
            raise TimekeeperError(f"the match has {len(self.cars)} cars, not {len(cars)}.")
        order = self.running_order()
        leader = order[0]
        started_at = self.started_at or now_iso()
        finishes = []
        for position, k in enumerate(order, start=1):
            heat = self.cars[k]
            named = cars[k]
            result: RaceResult = heat.result(
                racer=named.racer,
                car=named.car,
                car_hash=named.car_hash,
                track_name=track.name,
                track_hash=track.content_hash,
            )
            finishes.append(
                CarFinish(
                    position=position,
                    car=k,
                    finished_at=self.race_time(k) if self.finished(k) else None,
                    laps_completed=heat.laps_completed(),
                    # Metres of the laps it completed: where it stood in a lap is not timed.
                    distance=heat.laps_completed() * track.length,
                    gap_seconds=self.gap_seconds(leader, k),
                    result=result,
                )
            )
        clock = self.race_clock(0.0)  # every car's clock is stopped: any moment reads it
        return HeadToHeadResult(
            race_id=new_id(),
            track_name=track.name,
            track_hash=track.content_hash,
            rules=self.rules,
            seed=0,
            clock=round(clock, 3),
            cars=tuple(finishes),
            incidents=(),
            started_at=started_at,
        )

    # --- inside ----------------------------------------------------------------------------

    def _heat(self, car: int) -> TimekeptHeat:
        if not 0 <= car < len(self.cars):
            raise TimekeeperError(f"There is no car {car + 1} in this match.")
        return self.cars[car]

    def _input(
        self,
        car: int,
        now: float,
        give: Callable[[TimekeptHeat], str],
        *,
        once_ended: bool = False,
    ) -> str:
        """Give car `car`'s heat one input; what it did, naming the car (and the race's end
        when it came)."""
        heat = self._heat(car)
        if self.ended and not once_ended:
            raise TimekeeperError("The race was ended; nothing more is timed.")
        clock = self.race_clock(now)
        was = self.phase
        try:
            said = give(heat)
        except TimekeeperError as error:  # which car it is about, in a match of two
            raise TimekeeperError(f"Car {car + 1}: {error}") from None
        # A car's laps done end its own race, not the match's.
        said = said.replace("laps done: race over.", "laps done: finished.")
        # A car whose capture was taken back, or whose lap was struck, stopped its clocks
        # in its own heat; while the others race (or stand paused) it drove on all the
        # while, so its clock is theirs.
        others = [h for h in self.cars if h is not heat and h.phase in _RACING]
        if heat.phase is Phase.PAUSED and others:
            running = any(h.phase is Phase.RUNNING for h in others)
            heat.run_on(now, clock, running=running)
            if running:
                said = said.replace("the race is open again, paused", "it races on")
                said = said.replace("The race is open again, paused", "It races on")
        elif was is not Phase.OVER and self.phase is Phase.OVER:
            said = f"{said.rstrip()} Every car is done: race over."
        return f"Car {car + 1}: {said}"

    def _lap_times(self, car: int) -> list[float]:
        """The car's race time at each lap it completed (struck laps are none)."""
        heat = self.cars[car]
        times: list[float] = []
        penalties = 0.0
        for record, captured in zip(heat.lap_records(), heat.laps, strict=True):
            penalties += record.penalty_seconds
            if captured.finished and not captured.struck:
                times.append(round(record.started_at + record.raw_seconds + penalties, 3))
        return times

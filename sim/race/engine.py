"""The race engine: one car's time trial under league rules, on the simulation clock.

A race is one car on a `TrackSimulation` stepped at 15 Hz. It starts from a standstill on
the start line (waypoint 0, like `sim.physics.reference_driver.reference_lap`) and drives laps
continuously until the window closes (or, in a lap-count race, until it has completed its
laps). The race clock is the simulation clock, plus the
penalty holds (a hold lasts exactly its penalty, so a 2.5 s penalty costs 2.5 s, not
38 steps).

What happens when DeepRacer's episode rules trigger (a race never ends on them):
- Lap complete: the crossing time is interpolated inside the step, so lap times are not
  quantised to 1/15 s. The next lap starts at that instant; the car drives on.
- Off track (all four wheels off): the car is put back where DeepRacer puts it
  (`sim.physics.resets.reset_pose`: as far along the track as it had got one step before it left,
  on the lane nearer to where it was, pointing along the track, at speed zero) and held
  still for `penalty_seconds` while the race clock runs. The penalty is inside the lap
  time; the raw time (without it) is kept beside it. If a line crossing and an off-track
  happen in the same step, the lap completes (DeepRacer's precedence) and the off-track
  counts in the next lap.
- Reversed (15 steps of falling progress): the car is put back the same way, pointing
  along the track, and held for `penalty_seconds` like an off-track: someone has to pick it
  up. It counts as a reset, not an off-track, so it does not invalidate the lap; the
  driving the wrong way already cost time.
- Crashed (object avoidance and head-to-bot, `sim.physics.objects`): held for
  `collision_penalty_seconds` and counted in the lap's crashes. After hitting a box the car
  is put back 1 m behind it in the other lane, as DeepRacer does; after running into a bot
  from behind, put back like an off-track. The bots drive on while the car is held (simapp's
  do); they stop only when one of them runs into the car from behind.
- Immobilized: switched off. A car that does not move simply loses time until the window
  closes.
- A lap still in progress when the window closes does not count; its off-tracks still
  count towards the race's total.

Races are deterministic: the physics, the reference driver and policy drivers (argmax /
mean action) have no randomness, so the same driver, track, rules and seed give the same
laps. The seed is recorded with the result for drivers that do sample.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.ids import new_id
from sim.physics.car import DEEPRACER_CAR, STEP_SECONDS, CarSpec
from sim.physics.resets import put_back
from sim.physics.simulation import EpisodeRules, Outcome, TrackSimulation, let_other_threads_run
from sim.race.driver import Driver, reference_driver
from sim.race.result import LapRecord, RaceResult, completed_lap, now_iso
from sim.race.rules import DEFAULT_RULES, RaceRules, score_laps
from sim.race.trace import (
    CRASHED,
    IN_PROGRESS,
    LAP_COMPLETE,
    OFF_TRACK,
    PAUSE,
    PREPARE,
    REVERSED,
    TRACE_STATUSES,
    TraceRecorder,
)
from sim.tracks.track import Track

# DeepRacer's reversed rule stays; immobilized and the step limit are switched off (the
# window ends a race). 2**62 steps is longer than any window.
RACE_EPISODE_RULES = EpisodeRules(immobilized_steps=2**62, max_steps=2**62)
# Clock comparisons: far below a microsecond, far above float noise on a 1-hour clock.
_EPS = 1e-9


@dataclass(frozen=True)
class RaceTick:
    """One row of a race as a live view draws it; the last tick carries the result."""

    step: int  # row number: 0 is the car on the start line before it moves
    clock: float  # race clock, seconds
    window_seconds: float
    x: float  # car centre, metres
    y: float
    heading: float  # degrees, 0 = +x, counter-clockwise positive
    speed: float  # m/s
    lap: int  # lap in progress, 1-based
    lap_time: float  # time so far in the lap in progress, penalties included
    progress: float  # percent of the lap in progress
    laps: tuple[LapRecord, ...]  # completed laps so far
    lap_offtracks: int  # off-tracks in the lap in progress
    offtrack: bool  # the car left the track on this row
    status: str  # sim-trace status of this row: in_progress, off_track, pause, lap_complete ...
    penalty_remaining: float  # seconds of penalty hold still to serve
    result: RaceResult | None = None
    # The race's boxes or bot cars on this row: (x, y, heading in degrees) each.
    objects: tuple[tuple[float, float, float], ...] = ()
    lap_crashes: int = 0  # crashes into them in the lap in progress

    @property
    def finished(self) -> bool:
        return self.result is not None


class _Race:
    """The race's state between ticks; `tick` advances it by one row."""

    def __init__(
        self,
        track: Track,
        rules: RaceRules,
        driver: Driver,
        *,
        racer: str,
        seed: int,
        car: CarSpec,
        keep_trace: bool,
    ) -> None:
        self.track = track
        self.rules = rules
        self.driver = driver
        self.racer = racer
        self.seed = seed
        self.started_at = now_iso()
        self.sim = sim = TrackSimulation(
            track, 1, car=car, rules=RACE_EPISODE_RULES, race=rules.race_settings, seed=seed
        )
        sim.reset_car(0, start_s=0.0)
        driver.reset(sim)
        self.length = track.length
        self.window = rules.window_seconds
        self.drive_steps = 0
        self.held = 0.0  # total seconds of penalty holds served
        self.hold_left = 0.0
        self.row = 0
        self.lap = 1
        self.lap_start = 0.0
        self.lap_offtracks = 0
        self.lap_crashes = 0
        self.lap_reversals = 0
        self.lap_penalty = 0.0
        self.laps: list[LapRecord] = []
        self.laps_view: tuple[LapRecord, ...] = ()
        self.total_offtracks = 0
        self.status = PREPARE
        self.offtrack = False
        self.trace = (
            TraceRecorder(round(self.window / STEP_SECONDS) + 64, self.length)
            if keep_trace
            else None
        )
        self._record(self.lap)

    @property
    def clock(self) -> float:
        # Computed, not accumulated, so a long race does not gather rounding drift.
        return self.drive_steps * STEP_SECONDS + self.held

    @property
    def finished(self) -> bool:
        return self.rules.race_over(self.clock + _EPS, len(self.laps))

    def tick(self) -> None:
        if self.hold_left > 0.0:
            self._hold()
        else:
            self._drive()
        self.row += 1

    def _hold(self) -> None:
        served = min(STEP_SECONDS, self.hold_left, self.window - self.clock)
        self.held += served
        self.hold_left -= served
        if self.sim.objects is not None:
            self.sim.objects.pass_time(0, served)  # the bots drive on
        if self.hold_left < _EPS:
            self.hold_left = 0.0
        self.status = PAUSE
        self.offtrack = False
        self._record(self.lap)

    def _drive(self) -> None:
        sim = self.sim
        start = self.clock
        lap = self.lap
        before_travelled = float(sim.travelled[0])
        before_s = float(sim.s[0])
        before_x, before_y = float(sim.fleet.x[0]), float(sim.fleet.y[0])
        action = self.driver.act(sim)
        steering = float(action.steering_deg[0])
        throttle = float(action.speed[0])
        index = int(action.action_index[0])
        sim.apply(action.steering_deg, action.speed)
        self.drive_steps += 1
        # A Python int: numpy's int against an IntEnum member costs 4 µs (it probes the
        # enum class for array interfaces), a tenth of a race's step in physics.
        outcome = int(sim.terminal[0])
        self.offtrack = False
        pause = 0.0
        if outcome == Outcome.RUNNING:
            self.status = IN_PROGRESS
        else:
            status = sim.status[0]
            if status == EpisodeStatus.LAP_COMPLETE:
                self._lap_complete(start, before_travelled)
            elif status == EpisodeStatus.OFF_TRACK:
                self.offtrack = True
                self.lap_offtracks += 1
                self.total_offtracks += 1
                pause = self.rules.penalty_seconds
                self.status = OFF_TRACK
            elif status == EpisodeStatus.CRASHED:
                pause = self.rules.collision_penalty_seconds
                self.lap_crashes += 1
                self.status = CRASHED
            elif status == EpisodeStatus.REVERSED:
                pause = self.rules.penalty_seconds
                self.lap_reversals += 1
                self.status = REVERSED
            else:  # nothing else is switched on; drive on rather than stall the race
                sim.continue_episode(0, float(sim.travelled[0]))
                self.status = IN_PROGRESS
        self._record(
            lap,
            steering=steering,
            throttle=throttle,
            speed=float(sim.fleet.speed[0]),
            action=index,
            pause=pause,
        )
        if self.status in (OFF_TRACK, CRASHED, REVERSED):
            self._put_back(before_s, before_x, before_y, before_travelled)
            self._penalise(pause)

    def _penalise(self, seconds: float) -> None:
        self.lap_penalty += seconds
        self.hold_left = seconds

    def _lap_complete(self, start: float, before_travelled: float) -> None:
        sim = self.sim
        after = float(sim.travelled[0])
        fraction = (self.length - before_travelled) / max(after - before_travelled, 1e-12)
        crossing = start + min(max(fraction, 0.0), 1.0) * STEP_SECONDS
        sim.continue_episode(0, after - self.length)
        self.status = LAP_COMPLETE
        if crossing > self.window + _EPS:
            return  # the window closed before the line: the lap does not count
        lap = completed_lap(
            self.rules,
            number=self.lap,
            started_at=self.lap_start,
            time_seconds=crossing - self.lap_start,
            penalty_seconds=self.lap_penalty,
            offtracks=self.lap_offtracks,
            crashes=self.lap_crashes,
            reversals=self.lap_reversals,
        )
        self.laps.append(lap)
        self.laps_view = tuple(self.laps)
        self.lap += 1
        self.lap_start = crossing
        self.lap_offtracks = 0
        self.lap_crashes = 0
        self.lap_reversals = 0
        self.lap_penalty = 0.0

    def _put_back(self, s_ahead: float, car_x: float, car_y: float, travelled: float) -> None:
        """Put the car back where DeepRacer would, given where its look-ahead point
        (`s_ahead`) and its centre were a step before it left; progress follows it."""
        sim = self.sim
        pose = None
        if self.status == CRASHED and sim.objects is not None:
            behind = sim.objects.reset_behind(0, float(sim.s[0]))
            if behind is not None:  # DeepRacer: behind the box it hit, in the other lane
                pose = (behind.x, behind.y, behind.heading)
        put_back(sim, 0, s_ahead=s_ahead, car_x=car_x, car_y=car_y, travelled=travelled, pose=pose)

    def _record(
        self,
        lap: int,
        *,
        steering: float = 0.0,
        throttle: float = 0.0,
        speed: float = 0.0,
        action: int = -1,
        pause: float = 0.0,
    ) -> None:
        if self.trace is None:
            return
        sim = self.sim
        fleet = sim.fleet
        heading = math.degrees(float(fleet.yaw[0]))
        progress = float(sim.travelled[0]) / self.length * 100.0
        self.trace.add(
            t=self.clock,
            x=float(fleet.x[0]),
            y=float(fleet.y[0]),
            heading=180.0 - (180.0 - heading) % 360.0,
            speed=speed,
            steering=steering,
            throttle=throttle,
            action=action,
            status=self.status,
            lap=lap,
            offtrack=self.offtrack,
            all_wheels_on=bool(sim.wheels_on[0].all()),
            progress=min(max(progress, 0.0), 100.0),
            waypoint=int(sim.segment[0]),
            pause=pause,
        )

    def live_tick(self, result: RaceResult | None = None) -> RaceTick:
        sim = self.sim
        fleet = sim.fleet
        heading = math.degrees(float(fleet.yaw[0]))
        held = self.status == PAUSE or self.hold_left > 0.0
        return RaceTick(
            step=self.row,
            clock=min(self.clock, self.window),
            window_seconds=self.window,
            x=float(fleet.x[0]),
            y=float(fleet.y[0]),
            heading=180.0 - (180.0 - heading) % 360.0,
            speed=0.0 if held else float(fleet.speed[0]),
            lap=self.lap,
            lap_time=max(self.clock - self.lap_start, 0.0),
            progress=min(max(float(sim.travelled[0]) / self.length * 100.0, 0.0), 100.0),
            laps=self.laps_view,
            lap_offtracks=self.lap_offtracks,
            offtrack=self.offtrack,
            status=TRACE_STATUSES[self.status],
            penalty_remaining=self.hold_left,
            result=result,
            objects=self._objects(),
            lap_crashes=self.lap_crashes,
        )

    def _objects(self) -> tuple[tuple[float, float, float], ...]:
        field = self.sim.objects
        if field is None:
            return ()
        return tuple(
            (x, y, math.degrees(h))
            for x, y, h in zip(
                field.x[0].tolist(), field.y[0].tolist(), field.heading[0].tolist(), strict=True
            )
        )

    def result(self) -> RaceResult:
        trace = None if self.trace is None else self.trace.finish_race()
        laps = tuple(self.laps)
        return RaceResult(
            result_id=new_id(),
            racer=self.racer,
            model_name=self.driver.name,
            model_hash=self.driver.content_hash,
            track_name=self.track.name,
            track_hash=self.track.content_hash,
            rules=self.rules,
            seed=self.seed,
            laps=laps,
            scoring=score_laps(laps, self.rules),
            total_offtracks=self.total_offtracks,
            started_at=self.started_at,
            trace=trace,
            runtime=getattr(self.driver, "runtime", ""),
        )


def race_ticks(
    track: Track,
    rules: RaceRules = DEFAULT_RULES,
    driver: Driver | None = None,
    *,
    racer: str | None = None,
    seed: int = 0,
    car: CarSpec = DEEPRACER_CAR,
    keep_trace: bool = True,
) -> Generator[RaceTick, None, RaceResult]:
    """The race as a stream of ticks, one per row (1/15 s of race clock; shorter at the end
    of a penalty hold). The first tick is the car on the start line; the last carries the
    result (also the generator's return value). A live view paces them at 1x, 2x or 4x."""
    race = _start(track, rules, driver, racer=racer, seed=seed, car=car, keep_trace=keep_trace)
    yield race.live_tick()
    while not race.finished:
        race.tick()
        let_other_threads_run(race.row)
        if not race.finished:
            yield race.live_tick()
    result = race.result()
    yield race.live_tick(result)
    return result


def run_race(
    track: Track,
    rules: RaceRules = DEFAULT_RULES,
    driver: Driver | None = None,
    *,
    racer: str | None = None,
    seed: int = 0,
    car: CarSpec = DEEPRACER_CAR,
    keep_trace: bool = True,
) -> RaceResult:
    """Run a whole race as fast as the machine can; `driver` defaults to the reference driver."""
    race = _start(track, rules, driver, racer=racer, seed=seed, car=car, keep_trace=keep_trace)
    while not race.finished:
        race.tick()
        let_other_threads_run(race.row)
    return race.result()


def _start(
    track: Track,
    rules: RaceRules,
    driver: Driver | None,
    *,
    racer: str | None,
    seed: int,
    car: CarSpec,
    keep_trace: bool,
) -> _Race:
    if driver is None:
        driver = reference_driver(track, car)
    return _Race(
        track,
        rules,
        driver,
        racer=racer if racer is not None else driver.name,
        seed=seed,
        car=car,
        keep_trace=keep_trace,
    )

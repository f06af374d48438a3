"""A head-to-head race: two to six racers' cars on one track at once, each driven by its
own model, as simapp races HEAD_TO_MODEL (docs/deepracer/head-to-head-simapp.md).

- **The grid** is simapp's: car k starts 0.75 m behind car k-1 along the track
  (`START_POS_OFFSET`), even cars in the outer lane and odd cars in the inner one, each
  facing along its lane. A car behind the line drives its stagger on its first lap.
- **Lockstep:** every step, each car's driver acts on what its car senses (its camera and
  lidar see the other cars: `sim.physics.objects.rivals`), then every car moves 1/15 s.
  A driver that drives several cars acts for them in one batch.
- **Off track and reversed:** the car is put back on the track as in a time trial and held
  for the rules' `penalty_seconds`. **Crashed:** only the car behind is judged to have
  crashed; it is held for `collision_penalty_seconds` where it is (simapp does not move a
  car after a crash with another car). A held car is frozen, while the race clock and the
  other cars go on, and no car can run into it meanwhile.
- **The end:** a race of N laps (`lap_count`) ends when the first car completes its N-th
  lap (simapp's `DONE_CONDITION` "any"); the others are stopped where they are. Without
  a lap count the race runs for the whole window. It ends at the window in any case.
- **The order:** finished cars by the clock when they finished; then the others by how far
  they had got (laps, then distance into the lap). In a race for the window: most laps,
  then the best lap. simapp itself names no winner.

Races are deterministic, as time trials are: the same drivers, track, rules and seed give
the same race.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.ids import new_id
from sim.foundation.remedies import RemedyError
from sim.physics.car import DEEPRACER_CAR, STEP_SECONDS, CarSpec
from sim.physics.objects.placement import Lanes
from sim.physics.objects.rivals import CarPoses, Grid, RivalField
from sim.physics.objects.settings import Lane
from sim.physics.resets import put_back
from sim.physics.simulation import TrackSimulation, let_other_threads_run
from sim.race.driver import Driver, DriverAction
from sim.race.engine import RACE_EPISODE_RULES
from sim.race.result import LapRecord, RaceResult, completed_lap, now_iso
from sim.race.rules import RaceRules, score_laps
from sim.race.trace import (
    CRASHED,
    IN_PROGRESS,
    LAP_COMPLETE,
    OFF_TRACK,
    PAUSE,
    PREPARE,
    REVERSED,
    TraceRecorder,
)
from sim.tracks.track import Track

# simapp's START_POS_OFFSET: how far behind the car before it each car starts.
GRID_GAP = 0.75
MIN_CARS = 2
MAX_CARS = 6
# What an incident can be: a car ran into another from behind, or drove past it.
CRASH, OVERTAKE = "crash", "overtake"
INCIDENT_KINDS = (CRASH, OVERTAKE)
_EPS = 1e-9


class HeadToHeadError(RemedyError):
    """A head-to-head race that cannot be run as asked."""


@dataclass(frozen=True)
class Entry:
    """A car on the grid: who races it and what drives it."""

    racer: str
    driver: Driver


@dataclass(frozen=True)
class Incident:
    """Something the race view and the result tell: a crash or an overtake."""

    clock: float  # race clock, seconds
    kind: str  # "crash" (car ran into other from behind) or "overtake" (car passed other)
    car: int  # grid index
    other: int


@dataclass(frozen=True)
class CarFinish:
    """One car's race: its place, its laps and how far behind the winner it ended."""

    position: int  # 1-based
    car: int  # grid index
    finished_at: float | None  # race clock when it completed the race's laps
    laps_completed: int
    distance: float  # metres driven from the start line, laps included
    gap_seconds: float | None  # behind the winner: when the winner was where it ended
    result: RaceResult  # its laps, scored as a time trial's are


@dataclass(frozen=True)
class HeadToHeadResult:
    """A head-to-head race: the cars in finishing order and what happened on the way."""

    race_id: str
    track_name: str
    track_hash: str
    rules: RaceRules
    seed: int
    clock: float  # when the race ended
    cars: tuple[CarFinish, ...]  # in finishing order
    incidents: tuple[Incident, ...]
    started_at: str

    @property
    def winner(self) -> CarFinish:
        return self.cars[0]


@dataclass(frozen=True)
class _Before:
    """A car before the step: progress, look-ahead point along the track, centre."""

    travelled: float
    s: float
    x: float
    y: float


@dataclass
class CarInRace:
    """One car's race so far."""

    index: int
    entry: Entry
    lap_start: float = 0.0
    laps: list[LapRecord] = field(default_factory=list)
    lap_offtracks: int = 0
    lap_crashes: int = 0
    lap_reversals: int = 0
    lap_penalty: float = 0.0
    total_offtracks: int = 0
    hold_left: float = 0.0
    hold_for: str = ""  # why it is held: "crash", "off track" or "reversed"
    hold_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hold_travelled: float = 0.0
    finished_at: float | None = None
    trace: TraceRecorder | None = None
    # This step, for its trace row: what the car did and what came of it.
    status: int = PREPARE
    steering: float = 0.0
    throttle: float = 0.0
    action: int = -1
    pause: float = 0.0


class HeadToHeadRace:
    """The race between ticks: `tick` moves every car one step."""

    def __init__(
        self,
        track: Track,
        rules: RaceRules,
        entries: Sequence[Entry],
        *,
        seed: int = 0,
        car: CarSpec = DEEPRACER_CAR,
        keep_trace: bool = False,
    ) -> None:
        if not MIN_CARS <= len(entries) <= MAX_CARS:
            raise HeadToHeadError(
                f"a head-to-head race takes {MIN_CARS} to {MAX_CARS} cars, not {len(entries)}."
            )
        self.track = track
        self.rules = rules
        self.seed = seed
        self.started_at = now_iso()
        self.length = track.length
        n = len(entries)
        self.car_spec = car
        # A simulation for each car, with the time trial's one-car physics: a car drives
        # the laps it would drive alone. Its objects are the other cars (`RivalField`).
        self.sims = [
            TrackSimulation(track, 1, car=car, rules=RACE_EPISODE_RULES, seed=seed)
            for _ in range(n)
        ]
        self.grid = Grid.of([sim.fleet for sim in self.sims], track)
        self.cars = [CarInRace(index, entry) for index, entry in enumerate(entries)]
        self._line_up()
        self.rivals = [RivalField(track, k, self.grid) for k in range(n)]
        for sim, rivals, entry in zip(self.sims, self.rivals, entries, strict=True):
            sim.objects = rivals
            entry.driver.reset(sim)
        self.steps = 0
        if keep_trace:  # a sim-trace for each car, as simapp writes one for each agent
            rows = round(rules.window_seconds / STEP_SECONDS) + 64
            for entered in self.cars:
                entered.trace = TraceRecorder(rows, self.length)
                self._record(entered)
        self.incidents: list[Incident] = []
        self._order = self.running_order()
        # The furthest each car had got by each step (a put-back car may lose ground):
        # when a car first reached a distance, for the gaps.
        self._reach: list[np.ndarray] = [self.distances()]

    def _line_up(self) -> None:
        """simapp's grid (see the module docstring)."""
        lanes = Lanes.of(self.track)
        half = self.length / 2.0
        for k, sim in enumerate(self.sims):
            start = (-k * GRID_GAP) % self.length
            sim.reset_car(0, start)
            pose = lanes.pose(start, Lane.OUTER if k % 2 == 0 else Lane.INNER)
            sim.put(0, pose.x, pose.y, pose.heading, 0.0)
            # Progress from the start line itself: a car behind it starts below zero.
            sim.continue_episode(0, (float(sim.s[0]) + half) % self.length - half)
        self._update_standing()

    # --- where the cars are ------------------------------------------------------------
    @property
    def clock(self) -> float:
        return self.steps * STEP_SECONDS

    def distances(self) -> np.ndarray:
        """Metres each car has driven from the start line, its laps included."""
        return np.array(
            [
                len(car.laps) * self.length + float(sim.travelled[0])
                for car, sim in zip(self.cars, self.sims, strict=True)
            ]
        )

    def _update_standing(self) -> None:
        self.grid.standing = self.distances()

    def running_order(self) -> list[int]:
        """Grid indices, leader first: finished cars by when, then by distance."""
        distances = self.grid.standing  # `distances()`, kept current by every step
        return sorted(
            range(len(self.cars)),
            key=lambda k: (
                self.cars[k].finished_at is None,
                self.cars[k].finished_at or 0.0,
                -distances[k],
                k,
            ),
        )

    @property
    def order(self) -> list[int]:
        """The running order as the last step left it (`running_order`, kept by each
        step for its overtakes)."""
        return list(self._order)

    @property
    def finished(self) -> bool:
        if self.clock >= self.rules.window_seconds - _EPS:
            return True
        return self.rules.lap_count is not None and any(
            car.finished_at is not None for car in self.cars
        )

    # --- one step ------------------------------------------------------------------------
    def tick(self) -> None:
        """Every car drives one step (each on what it sensed before any moved), then each
        is judged where all of them are now."""
        driving = [car for car in self.cars if car.hold_left <= 0.0]
        actions = self._actions(driving)
        before: dict[int, _Before] = {}
        for car in self.cars:
            sim = self.sims[car.index]
            action = actions.get(car.index)
            before[car.index] = _Before(
                float(sim.travelled[0]),
                float(sim.s[0]),
                float(sim.fleet.x[0]),
                float(sim.fleet.y[0]),
            )
            car.pause = 0.0
            if action is None:  # held: it stands, and is put back where it was frozen
                car.steering = car.throttle = 0.0
                car.action = -1
                sim.apply(np.zeros(1), np.zeros(1))
            else:
                car.steering, car.throttle = float(action.steering_deg[0]), float(action.speed[0])
                car.action = int(action.action_index[0])
                sim.apply(action.steering_deg[:1], action.speed[:1])
        start = self.clock
        self.steps += 1
        poses = self._follow()
        self._update_standing()
        crashes = self.grid.crashes([car.index for car in driving], self.car_spec, poses)
        for car in self.cars:
            if car.hold_left > 0.0:
                self._hold(car)
            else:
                self._judge(car, start, before[car.index], crashes[car.index])
        self._follow()  # where the put-back cars stand now
        self._update_standing()
        for car in self.cars:
            self._record(car)
        self._note_overtakes()
        self._reach.append(np.maximum(self._reach[-1], self.grid.standing))

    def _follow(self) -> CarPoses:
        """Every car's rivals where the other cars stand now (those poses, returned)."""
        poses = self.grid.poses()
        for rivals in self.rivals:
            rivals.follow(poses)
        return poses

    def _actions(self, driving: list[CarInRace]) -> dict[int, DriverAction]:
        """Each driving car's action; a driver that can (`act_many`: a policy) acts for
        all its cars in one batch."""
        by_driver: dict[int, list[CarInRace]] = {}
        for car in driving:
            by_driver.setdefault(id(car.entry.driver), []).append(car)
        actions: dict[int, DriverAction] = {}
        for cars in by_driver.values():
            driver = cars[0].entry.driver
            sims = [self.sims[car.index] for car in cars]
            act_many = getattr(driver, "act_many", None)
            if act_many is not None and len(cars) > 1:
                for car, action in zip(cars, act_many(sims), strict=True):
                    actions[car.index] = action
            else:
                for car, sim in zip(cars, sims, strict=True):
                    actions[car.index] = driver.act(sim)
        return actions

    def _hold(self, car: CarInRace) -> None:
        """A held car stays where it was frozen (simapp resets its pose every step)."""
        sim = self.sims[car.index]
        x, y, yaw = car.hold_pose
        sim.put(0, x, y, yaw, 0.0)
        sim.continue_episode(0, car.hold_travelled)
        car.status = PAUSE
        car.hold_left -= STEP_SECONDS
        if car.hold_left < _EPS:
            car.hold_left = 0.0
            self.grid.ghost[car.index] = False

    def _judge(
        self, car: CarInRace, start: float, before: _Before, crashed_into: list[int]
    ) -> None:
        """What the step did to a car that was driving, in DeepRacer's precedence: a lap
        completed, then a crash, then off track, then turned round."""
        sim = self.sims[car.index]
        car.status = IN_PROGRESS
        if not sim.terminal[0] and not crashed_into:
            return  # most steps: it drove on
        status = sim.status[0] if sim.terminal[0] else None
        if status == EpisodeStatus.LAP_COMPLETE:
            car.status = LAP_COMPLETE
            self._lap_complete(car, start, before.travelled)
        elif crashed_into:
            car.status = CRASHED
            car.lap_crashes += 1
            for other in crashed_into:
                self.incidents.append(Incident(self.clock, CRASH, car.index, other))
            sim.continue_episode(0, float(sim.travelled[0]))  # held where it is
            self._penalise(car, self.rules.collision_penalty_seconds, "crash")
        elif status == EpisodeStatus.OFF_TRACK:
            car.status = OFF_TRACK
            car.lap_offtracks += 1
            car.total_offtracks += 1
            self._put_back(car, before)
            self._penalise(car, self.rules.penalty_seconds, "off track")
        elif status == EpisodeStatus.REVERSED:
            car.status = REVERSED
            car.lap_reversals += 1
            self._put_back(car, before)
            self._penalise(car, self.rules.penalty_seconds, "reversed")
        elif status is not None:  # nothing else is switched on in a race
            sim.continue_episode(0, float(sim.travelled[0]))

    def _record(self, car: CarInRace) -> None:
        """The car's sim-trace row for this step (the time trial's columns)."""
        if car.trace is None:
            return
        sim = self.sims[car.index]
        fleet = sim.fleet
        heading = math.degrees(float(fleet.yaw[0]))
        progress = float(sim.travelled[0]) / self.length * 100.0
        car.trace.add(
            t=min(self.clock, self.rules.window_seconds),
            x=float(fleet.x[0]),
            y=float(fleet.y[0]),
            heading=180.0 - (180.0 - heading) % 360.0,
            speed=0.0 if car.status == PAUSE else float(fleet.speed[0]),
            steering=car.steering,
            throttle=car.throttle,
            action=car.action,
            status=car.status,
            lap=len(car.laps) + (0 if car.status == LAP_COMPLETE else 1),
            offtrack=car.status == OFF_TRACK,
            all_wheels_on=bool(sim.wheels_on[0].all()),
            progress=min(max(progress, 0.0), 100.0),
            waypoint=int(sim.segment[0]),
            pause=car.pause,
        )

    def _lap_complete(self, car: CarInRace, start: float, before_travelled: float) -> None:
        sim = self.sims[car.index]
        after = float(sim.travelled[0])
        fraction = (self.length - before_travelled) / max(after - before_travelled, 1e-12)
        crossing = start + min(max(fraction, 0.0), 1.0) * STEP_SECONDS
        sim.continue_episode(0, after - self.length)
        if crossing > self.rules.window_seconds + _EPS:
            return
        lap = completed_lap(
            self.rules,
            number=len(car.laps) + 1,
            started_at=car.lap_start,
            time_seconds=crossing - car.lap_start,
            penalty_seconds=car.lap_penalty,
            offtracks=car.lap_offtracks,
            crashes=car.lap_crashes,
            reversals=car.lap_reversals,
        )
        car.laps.append(lap)
        car.lap_start = crossing
        car.lap_offtracks = car.lap_crashes = car.lap_reversals = 0
        car.lap_penalty = 0.0
        if self.rules.lap_count is not None and len(car.laps) >= self.rules.lap_count:
            car.finished_at = crossing

    def _put_back(self, car: CarInRace, before: _Before) -> None:
        """Where DeepRacer puts a car back after an off-track or reversing: as far along as
        its look-ahead point was a step before, on the nearer lane."""
        put_back(
            self.sims[car.index],
            0,
            s_ahead=before.s,
            car_x=before.x,
            car_y=before.y,
            travelled=before.travelled,
        )

    def _penalise(self, car: CarInRace, seconds: float, why: str) -> None:
        sim = self.sims[car.index]
        fleet = sim.fleet
        car.lap_penalty += seconds
        car.hold_left = car.pause = seconds
        car.hold_for = why
        car.hold_pose = (float(fleet.x[0]), float(fleet.y[0]), float(fleet.yaw[0]))
        car.hold_travelled = float(sim.travelled[0])
        if seconds > 0.0:
            self.grid.ghost[car.index] = True

    def _note_overtakes(self) -> None:
        """A car that drove past another this step overtook it. A change of order because
        a car was put back behind another, or while the passing car stood held, is not an
        overtake (two held cars put back in turn swapped places step after step)."""
        order = self.running_order()
        before = {car: place for place, car in enumerate(self._order)}
        for place, car in enumerate(order):
            if self.cars[car].status not in (IN_PROGRESS, LAP_COMPLETE):
                continue
            for passed in order[place + 1 :]:
                put_back = self.cars[passed].status in (OFF_TRACK, REVERSED)
                if before[car] > before[passed] and not put_back:
                    self.incidents.append(Incident(self.clock, OVERTAKE, car, passed))
        self._order = order

    # --- the end -------------------------------------------------------------------------
    def result(self) -> HeadToHeadResult:
        order = self._final_order()
        distances = self.distances()
        leader = order[0]
        finishes = []
        for position, k in enumerate(order, start=1):
            car = self.cars[k]
            finishes.append(
                CarFinish(
                    position=position,
                    car=k,
                    finished_at=car.finished_at,
                    laps_completed=len(car.laps),
                    distance=float(distances[k]),
                    gap_seconds=self._gap(leader, k),
                    result=self._car_result(car),
                )
            )
        return HeadToHeadResult(
            race_id=new_id(),
            track_name=self.track.name,
            track_hash=self.track.content_hash,
            rules=self.rules,
            seed=self.seed,
            clock=min(self.clock, self.rules.window_seconds),
            cars=tuple(finishes),
            incidents=tuple(self.incidents),
            started_at=self.started_at,
        )

    def _final_order(self) -> list[int]:
        if self.rules.lap_count is not None:
            return self.running_order()

        def best(k: int) -> float:
            times = [lap.time_seconds for lap in self.cars[k].laps if lap.valid]
            return min(times, default=float("inf"))

        return sorted(range(len(self.cars)), key=lambda k: (-len(self.cars[k].laps), best(k), k))

    def _gap(self, leader: int, k: int) -> float | None:
        """The gap at the end (`gap_seconds`, to when car `k` finished or the race did)."""
        ended = self.cars[k].finished_at
        return self.gap_seconds(
            leader, k, ended if ended is not None else min(self.clock, self.rules.window_seconds)
        )

    def gap_seconds(self, leader: int, k: int, at: float | None = None) -> float | None:
        """How long before `at` (now by default) the leader was where car `k` is: the gap
        a timing screen shows. None when the leader never was there (it started behind)."""
        if k == leader:
            return 0.0
        target = float(self.grid.standing[k])
        steps = bisect_left(self._reach, target, key=lambda reach: float(reach[leader]))
        if steps == len(self._reach):
            return None
        return round((self.clock if at is None else at) - steps * STEP_SECONDS, 3)

    def _car_result(self, car: CarInRace) -> RaceResult:
        laps = tuple(car.laps)
        trace = None if car.trace is None else car.trace.finish_race()
        return RaceResult(
            result_id=new_id(),
            racer=car.entry.racer,
            model_name=car.entry.driver.name,
            model_hash=car.entry.driver.content_hash,
            track_name=self.track.name,
            track_hash=self.track.content_hash,
            rules=self.rules,
            seed=self.seed,
            laps=laps,
            scoring=score_laps(laps, self.rules),
            total_offtracks=car.total_offtracks,
            started_at=self.started_at,
            trace=trace,
            # The policy runtime that drove this car, as a time trial records it.
            runtime=getattr(car.entry.driver, "runtime", ""),
        )


def run_head_to_head(
    track: Track,
    rules: RaceRules,
    entries: Sequence[Entry],
    *,
    seed: int = 0,
    car: CarSpec = DEEPRACER_CAR,
    keep_trace: bool = False,
) -> HeadToHeadResult:
    """Run a whole head-to-head race as fast as the machine can; `keep_trace` keeps each
    car's sim-trace with its result."""
    race = HeadToHeadRace(track, rules, entries, seed=seed, car=car, keep_trace=keep_trace)
    while not race.finished:
        race.tick()
        let_other_threads_run(race.steps)
    return race.result()

"""A head-to-head race as a live view draws it: one tick per step with every car's pose,
lap and penalty hold, the running order with each car's gap to the leader, and what
happened on the step (crashes, overtakes); the last tick carries the result.

The view (racer_tui.app.screens.head_to_head_screen) plays the ticks back against a wall
clock, as the time trial's view plays `sim.race.engine.race_ticks`.
"""

from __future__ import annotations

import math
from collections.abc import Generator, Sequence
from dataclasses import dataclass

from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.physics.simulation import let_other_threads_run
from sim.race.head_to_head import (
    CarInRace,
    Entry,
    HeadToHeadRace,
    HeadToHeadResult,
    Incident,
)
from sim.race.rules import RaceRules
from sim.tracks.track import Track


@dataclass(frozen=True)
class CarTick:
    """One car on one tick."""

    x: float  # car centre, metres
    y: float
    heading: float  # degrees, 0 = +x, counter-clockwise positive
    speed: float  # m/s; 0 while held
    lap: int  # the lap it is on, 1-based (the last one it completed once it has finished)
    laps_completed: int
    best_lap: float | None  # its fastest counted lap so far, seconds
    crashes: int  # into other cars, the whole race
    offtracks: int  # the whole race
    held: float  # seconds of penalty hold still to serve
    held_for: str  # why: "crash", "off track" or "reversed" ("" when not held)
    finished: bool  # completed the race's laps


@dataclass(frozen=True)
class HeadToHeadTick:
    """Every car on one step of the race."""

    step: int  # 0 is the grid before any car moves
    clock: float  # race clock, seconds
    cars: tuple[CarTick, ...]  # in grid order
    order: tuple[int, ...]  # grid indices, leader first
    gaps: tuple[float | None, ...]  # in grid order: seconds behind the leader (None: not yet)
    incidents: tuple[Incident, ...] = ()  # what happened on this step
    result: HeadToHeadResult | None = None


def _car_tick(race: HeadToHeadRace, car: CarInRace) -> CarTick:
    fleet = race.sims[car.index].fleet
    lap_count = race.rules.lap_count
    laps = len(car.laps)
    lap = laps + 1 if lap_count is None else min(laps + 1, lap_count)
    valid = [lap.time_seconds for lap in car.laps if lap.valid]
    held = car.hold_left > 0.0
    return CarTick(
        x=float(fleet.x[0]),
        y=float(fleet.y[0]),
        heading=math.degrees(float(fleet.yaw[0])),
        speed=0.0 if held else float(fleet.speed[0]),
        lap=lap,
        laps_completed=laps,
        best_lap=min(valid, default=None),
        crashes=sum(lap.crashes for lap in car.laps) + car.lap_crashes,
        offtracks=car.total_offtracks,
        held=car.hold_left,
        held_for=car.hold_for if held else "",
        finished=car.finished_at is not None,
    )


def live_tick(
    race: HeadToHeadRace,
    incidents: Sequence[Incident] = (),
    result: HeadToHeadResult | None = None,
) -> HeadToHeadTick:
    """The race as it stands now."""
    order = race.order if result is None else [finish.car for finish in result.cars]
    leader = order[0]
    if result is None:
        gaps = tuple(race.gap_seconds(leader, k) for k in range(len(race.cars)))
    else:
        by_car = {finish.car: finish.gap_seconds for finish in result.cars}
        gaps = tuple(by_car[k] for k in range(len(race.cars)))
    return HeadToHeadTick(
        step=race.steps,
        clock=min(race.clock, race.rules.window_seconds),
        cars=tuple(_car_tick(race, car) for car in race.cars),
        order=tuple(order),
        gaps=gaps,
        incidents=tuple(incidents),
        result=result,
    )


def head_to_head_ticks(
    track: Track,
    rules: RaceRules,
    entries: Sequence[Entry],
    *,
    seed: int = 0,
    car: CarSpec = DEEPRACER_CAR,
) -> Generator[HeadToHeadTick, None, HeadToHeadResult]:
    """The race as a stream of ticks, one per step (1/15 s of race clock): the first is the
    grid, the last carries the result (also the generator's return value). The race is
    the one `run_head_to_head` runs with the same arguments."""
    race = HeadToHeadRace(track, rules, entries, seed=seed, car=car)
    yield live_tick(race)
    while True:
        seen = len(race.incidents)
        race.tick()
        let_other_threads_run(race.steps)
        if race.finished:
            break
        yield live_tick(race, race.incidents[seen:])
    result = race.result()
    yield live_tick(race, race.incidents[seen:], result)
    return result

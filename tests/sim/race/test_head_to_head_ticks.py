"""The head-to-head race as the live view draws it: the stream of ticks is the race that
`run_head_to_head` runs, its incidents arrive on the step they happen, and its live gaps
are the timing screen's (how long ago the leader was where each car is)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from sim.physics.car import STEP_SECONDS
from sim.physics.simulation import TrackSimulation
from sim.race.driver import Driver, DriverAction, reference_driver
from sim.race.head_to_head import Entry, HeadToHeadRace, HeadToHeadResult, run_head_to_head
from sim.race.head_to_head_ticks import HeadToHeadTick, head_to_head_ticks
from sim.race.rules import HEAD_TO_HEAD_RULES
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

ONE_LAP = replace(HEAD_TO_HEAD_RULES, lap_count=1)


class _Slowed:
    """A driver that drives `driver`'s line at a fraction of its speed."""

    def __init__(self, driver: Driver, fraction: float) -> None:
        self.driver = driver
        self.fraction = fraction
        self.name = f"slowed {driver.name}"
        self.content_hash = f"slowed:{driver.content_hash}"

    def reset(self, sim: TrackSimulation) -> None:
        self.driver.reset(sim)

    def act(self, sim: TrackSimulation) -> DriverAction:
        action = self.driver.act(sim)
        return DriverAction(action.steering_deg, action.speed * self.fraction, action.action_index)


@pytest.fixture(scope="module")
def track() -> Track:
    return resolve_track("reinvent_base")


def _entries(track: Track) -> list[Entry]:
    """A slow car on the front of the grid and the reference driver behind it: the
    reference driver passes it at once, and the slow car runs into it."""
    return [
        Entry("slow", _Slowed(reference_driver(track), 0.4)),
        Entry("quick", reference_driver(track)),
    ]


def _summary(result: HeadToHeadResult) -> list[tuple[int, float | None, tuple[float, ...]]]:
    return [
        (finish.car, finish.gap_seconds, tuple(lap.time_seconds for lap in finish.result.laps))
        for finish in result.cars
    ]


@pytest.fixture(scope="module")
def ticks(track: Track) -> list[HeadToHeadTick]:
    return list(head_to_head_ticks(track, ONE_LAP, _entries(track)))


def test_the_ticks_are_the_race_run_headless(track: Track, ticks: list[HeadToHeadTick]) -> None:
    headless = run_head_to_head(track, ONE_LAP, _entries(track))
    streamed = ticks[-1].result
    assert streamed is not None
    assert _summary(streamed) == _summary(headless)
    assert streamed.incidents == headless.incidents
    assert [finish.car for finish in streamed.cars] == [1, 0]  # the quick car won
    # One tick per step, the grid first; only the last carries the result.
    assert [tick.step for tick in ticks] == list(range(len(ticks)))
    assert ticks[0].clock == 0.0 and all(tick.result is None for tick in ticks[:-1])
    # Every incident arrives once, on its own step.
    arrived = [incident for tick in ticks for incident in tick.incidents]
    assert arrived == list(streamed.incidents)
    assert [incident.kind for incident in arrived] == ["overtake", "crash"]
    for tick in ticks:
        assert all(incident.clock == pytest.approx(tick.clock) for incident in tick.incidents)


def test_each_tick_says_where_every_car_is_and_how_far_behind(ticks: list[HeadToHeadTick]) -> None:
    first = ticks[0]
    assert first.order == (0, 1) and first.gaps[0] == 0.0
    assert first.gaps[1] == 0.0  # on the grid together: the leader was there just now
    for tick in ticks:
        assert tick.gaps[tick.order[0]] == 0.0
        assert sorted(tick.order) == [0, 1]
    last = ticks[-1]
    assert last.result is not None
    assert last.gaps == tuple(
        {finish.car: finish.gap_seconds for finish in last.result.cars}[k] for k in (0, 1)
    )
    winner = last.cars[1]
    assert winner.finished and winner.laps_completed == 1 and winner.lap == 1
    assert winner.best_lap == last.result.cars[0].result.laps[0].time_seconds
    assert not last.cars[0].finished and last.cars[0].laps_completed == 0
    # A held car stands: its speed is 0 for as long as its hold lasts.
    held = [car for tick in ticks for car in tick.cars if car.held > 0]
    assert all(car.speed == 0.0 for car in held)


def test_a_live_gap_is_when_the_leader_was_where_the_car_is(track: Track) -> None:
    race = HeadToHeadRace(track, ONE_LAP, _entries(track))
    history: list[np.ndarray] = [race.distances()]
    checked = 0
    while not race.finished:
        race.tick()
        history.append(race.distances())
        if race.steps % 10:
            continue
        leader = race.running_order()[0]
        for k in range(2):
            target = float(history[-1][k])
            steps = next((i for i, d in enumerate(history) if d[leader] >= target), None)
            expected = None if steps is None else round(race.clock - steps * STEP_SECONDS, 3)
            gap = race.gap_seconds(leader, k)
            assert gap == (0.0 if k == leader else expected)
            checked += gap is not None and gap > 0
    assert checked > 5

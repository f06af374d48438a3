"""A bracket match between two physical cars, timed by hand: one race clock, a lap key per
car, penalties added to each car's race time, and a journal that brings the match back."""

from __future__ import annotations

from pathlib import Path

import pytest

from league.timekeeper.heat import Phase, TimekeeperError
from league.timekeeper.journal import (
    HeatJournal,
    resume_heat,
    resume_match,
    take_match_input,
)
from league.timekeeper.match import MatchCar, TimekeptMatch
from sim.physics.labels import PHYSICAL
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.catalog import resolve_track

RULES = HEAD_TO_HEAD_RULES  # 3 laps, 2 s a reset
CARS = [MatchCar("ana", "red", "physical-red"), MatchCar("bob", "blue", "physical-blue")]


def raced(inputs: list[tuple[str, float, int]]) -> TimekeptMatch:
    match = TimekeptMatch(RULES)
    for kind, at, car in inputs:
        take_match_input(match, kind, at, None, car)
    return match


def test_the_first_car_over_the_line_can_lose_on_its_penalties() -> None:
    match = raced(
        [
            ("start_or_pause", 0.0, 0),
            ("reset", 3.0, 0),
            ("reset", 4.0, 0),  # car 1: two resets, 4 s of penalties
            ("capture", 10.0, 0),
            ("capture", 10.5, 1),
            ("capture", 20.0, 0),
            ("capture", 21.0, 1),
            ("capture", 30.0, 0),  # car 1 crosses first after 3 laps: 30 s + 4 s
        ]
    )
    assert match.phase is Phase.RUNNING  # car 2 still drives its last lap
    assert match.finished(0) and match.race_time(0) == 34.0
    said = match.capture(1, 32.0)  # car 2: 32 s, no penalty
    assert said.startswith("Car 2: Lap 3") and said.endswith("race over.")
    assert match.phase is Phase.OVER
    assert match.running_order() == [1, 0]
    assert match.gap_seconds(1, 0) == 2.0

    result = match.result(resolve_track("reinvent_base"), CARS)
    assert [finish.result.racer for finish in result.cars] == ["bob", "ana"]
    assert [finish.finished_at for finish in result.cars] == [32.0, 34.0]
    assert {finish.result.physics for finish in result.cars} == {PHYSICAL}
    assert result.cars[1].result.total_offtracks == 2 and result.seed == 0
    assert result.clock == 32.0 and result.incidents == ()


def test_one_clock_for_both_cars_paused_and_started_together() -> None:
    match = raced([("start_or_pause", 0.0, 0), ("capture", 10.0, 1)])
    assert match.start_or_pause(12.0).startswith("Paused")
    with pytest.raises(TimekeeperError, match="paused"):
        match.capture(0, 13.0)
    assert match.race_clock(100.0) == 12.0  # stopped for both
    match.start_or_pause(50.0)
    match.capture(0, 58.0)  # 12 s before the pause and 8 after it
    assert match.cars[0].lap_records()[0].raw_seconds == 20.0
    assert match.race_clock(58.0) == 20.0


def test_a_false_finish_taken_back_races_on_with_the_others() -> None:
    match = raced(
        [("start_or_pause", 0.0, 0)]
        + [("capture", 10.0 * lap, 0) for lap in (1, 2, 3)]  # car 1 "finished" at 30 s
        + [("capture", 11.0, 1)]
    )
    assert match.finished(0) and match.phase is Phase.RUNNING
    said = match.undo_capture(0, 33.0)
    assert said == "Car 1: Lap 3 taken back: it races on."
    assert match.cars[0].phase is Phase.RUNNING
    assert match.cars[0].lap_clock(33.0) == pytest.approx(13.0)  # its third lap went on
    match.capture(0, 35.0)
    assert match.race_time(0) == 35.0


def test_a_retired_car_keeps_its_laps_and_ranks_behind_a_finisher() -> None:
    match = raced([("start_or_pause", 0.0, 0), ("capture", 10.0, 0), ("capture", 11.0, 1)])
    assert match.retire(0, 15.0) == "Car 1: retired: its completed laps stand."
    with pytest.raises(TimekeeperError, match="Car 1: Its race is over already"):
        match.retire(0, 16.0)
    # The walk: u after a retire took back a lap the car had driven.
    with pytest.raises(TimekeeperError, match="Car 1 is retired: its completed laps stand"):
        match.undo_capture(0, 16.0)
    assert match.running_order() == [1, 0]  # it forfeits: behind, with a lap more
    match.capture(1, 22.0)
    said = match.capture(1, 33.0)
    assert said.endswith("Every car is done: race over.")
    assert match.running_order() == [1, 0]
    assert match.gap_seconds(1, 0) is None  # it was ahead after one lap: not a gap
    result = match.result(resolve_track("reinvent_base"), CARS)
    assert [finish.laps_completed for finish in result.cars] == [3, 1]
    assert result.cars[1].finished_at is None


def test_ending_the_race_ranks_by_laps_then_race_time() -> None:
    match = raced(
        [
            ("start_or_pause", 0.0, 0),
            ("capture", 10.0, 0),
            ("capture", 9.0, 1),
            ("reset", 12.0, 1),
            ("capture", 19.0, 1),  # car 2: two laps, 19 s + 2 s
        ]
    )
    assert match.end(25.0) == "Race over."
    assert match.phase is Phase.OVER
    with pytest.raises(TimekeeperError, match="ended"):
        match.capture(0, 26.0)
    assert match.running_order() == [1, 0]  # more laps first
    assert match.gap_seconds(1, 0) == pytest.approx(1.0)  # 10 s against its first lap's 9
    # A lap struck out once the race is ended changes the order the host records.
    assert match.strike(1, 1, 26.0) == "Car 2: Lap 1 struck out."
    assert match.running_order() == [0, 1]  # one lap each: car 1's at 10 s, car 2's at 21 s


def test_a_race_for_the_window_goes_to_most_laps_then_the_best() -> None:
    rules = RaceRules(window_seconds=30.0, penalty_seconds=2.0, race_type=RULES.race_type)
    match = TimekeptMatch(rules)
    match.start_or_pause(0.0)
    for at in (9.0, 18.0, 27.0, 36.0):  # the fourth lap ends the car's race: time was up
        match.capture(0, at)
    for at in (8.0, 17.0, 26.0):
        match.capture(1, at)
    assert match.phase is Phase.RUNNING
    match.capture(1, 35.0)
    assert match.phase is Phase.OVER
    assert match.running_order() == [1, 0]  # 4 laps each, car 2's first lap the best


def test_a_match_refuses_what_cannot_be() -> None:
    with pytest.raises(TimekeeperError, match="2 to 6 cars"):
        TimekeptMatch(RULES, 1)
    match = TimekeptMatch(RULES)
    with pytest.raises(TimekeeperError, match="start the race first"):
        match.capture(0, 1.0)
    with pytest.raises(TimekeeperError, match="no car 3"):
        match.capture(2, 1.0)
    with pytest.raises(TimekeeperError, match="has not started"):
        match.end(1.0)
    match.start_or_pause(0.0)
    with pytest.raises(TimekeeperError, match="still on"):
        match.result(resolve_track("reinvent_base"), CARS)


def test_a_match_comes_back_from_its_journal_paused(tmp_path: Path) -> None:
    path = tmp_path / "match.json"
    key = "01JDR00000000000000NIGHT1-W1-1"
    match = TimekeptMatch(RULES)
    journal = HeatJournal(path, key, cars=2)
    inputs = [("start_or_pause", 0.0, 0), ("reset", 4.0, 1), ("capture", 10.0, 1)]
    for kind, at, car in inputs:
        take_match_input(match, kind, at, None, car)
        journal.took(kind, at, match, car=car)
    journal.heartbeat(14.5)
    journal.close()

    resumed = resume_match(path, key, RULES, 2)
    assert resumed is not None and resumed.stopped and resumed.at == 14.5
    again = resumed.match
    assert again.phase is Phase.PAUSED and again.started_at == match.started_at
    assert again.cars[1].lap_records() == match.cars[1].lap_records()
    assert again.cars[0].lap_clock(99.0) == pytest.approx(14.5)
    # Not a heat's journal, nor one of three cars; a car the match has not is no journal.
    assert resume_heat(path, key, RULES) is None
    assert resume_match(path, key, RULES, 3) is None
    text = path.read_text()
    path.write_text(text.replace('"capture", 10.0, null, 1', '"capture", 10.0, null, 5'))
    assert resume_match(path, key, RULES, 2) is None


def test_a_false_finish_taken_back_while_paused_keeps_the_race_clock() -> None:
    """Car 1 "finished" at 30 s; the host paused at 33 s and then took the capture back:
    its lap ran on until the pause, and goes on with the others' clock when they start."""
    match = raced(
        [("start_or_pause", 0.0, 0)]
        + [("capture", 10.0 * lap, 0) for lap in (1, 2, 3)]
        + [("capture", 11.0, 1), ("start_or_pause", 33.0, 0)]
    )
    match.undo_capture(0, 40.0)
    assert match.phase is Phase.PAUSED
    assert match.cars[0].race_clock(40.0) == 33.0 == match.cars[1].race_clock(40.0)
    match.start_or_pause(50.0)
    match.capture(0, 52.0)  # 35 s of race time: its third lap took 15 s
    assert match.race_time(0) == 35.0

"""A physical car's heat, timed by hand: clocks, laps, resets and the result it makes."""

from __future__ import annotations

import pytest

from league.leaderboard import Filters, leaderboard
from league.opening import open_league
from league.races import record_race
from league.timekeeper.heat import Phase, TimekeeperError, TimekeptHeat
from sim.physics.labels import PHYSICAL
from sim.race.result import RaceResult
from sim.race.rules import RaceRules

RULES = RaceRules(window_seconds=60.0, penalty_seconds=2.0, max_offtracks_per_lap=3)


def result_of(heat: TimekeptHeat) -> RaceResult:
    return heat.result(
        racer="Ada", car="blue car", car_hash="physical", track_name="re:Invent 2018",
        track_hash="t" * 16,
    )  # fmt: skip


def test_clocks_run_only_while_running_and_laps_carry_their_resets() -> None:
    heat = TimekeptHeat(RULES)
    assert heat.phase is Phase.READY and heat.time_left(100.0) == 60.0
    heat.start_or_pause(100.0)
    assert heat.lap_clock(109.5) == pytest.approx(9.5)
    heat.reset(104.0)
    assert heat.capture(109.5) == "Lap 1: 11.500 s, counts."  # 9.5 s + one 2 s penalty
    heat.start_or_pause(112.0)  # paused 2.5 s into lap 2 ...
    assert heat.time_left(500.0) == pytest.approx(60.0 - 12.0)  # ... the clocks stand still
    heat.start_or_pause(200.0)
    for moment in (200.5, 201.0, 201.5, 202.0):
        heat.reset(moment)
    said = heat.capture(207.0)
    assert "does not count" in said  # four resets, over the limit of three
    lap1, lap2 = heat.lap_records()
    assert (lap1.raw_seconds, lap1.penalty_seconds, lap1.offtracks, lap1.valid) == (
        9.5,
        2.0,
        1,
        True,
    )
    assert lap2.raw_seconds == pytest.approx(9.5) and lap2.offtracks == 4 and not lap2.valid
    assert lap2.started_at == pytest.approx(9.5)


def test_time_up_ends_the_race_at_the_next_capture_and_a_false_finish_reopens_it() -> None:
    heat = TimekeptHeat(RULES)
    heat.start_or_pause(0.0)
    heat.capture(30.0)
    assert heat.expired(61.0) and heat.time_left(61.0) == 0.0
    assert heat.phase is Phase.RUNNING  # the lap in progress at zero may still finish
    assert heat.capture(62.0).endswith("Time is up: race over.")
    assert heat.phase is Phase.OVER and [lap.raw_seconds for lap in heat.laps] == [30.0, 32.0]
    with pytest.raises(TimekeeperError, match="race is over"):
        heat.reset(63.0)
    # The capture at 62 s was a false finish: the lap goes on, paused.
    heat.undo_capture(64.0)
    assert heat.phase is Phase.PAUSED and len(heat.laps) == 1
    heat.start_or_pause(70.0)
    heat.capture(75.0)
    assert heat.phase is Phase.OVER and heat.laps[-1].raw_seconds == pytest.approx(37.0)


def test_a_lap_count_race_is_over_at_the_capture_of_its_last_driven_lap() -> None:
    heat = TimekeptHeat(RaceRules(window_seconds=60.0, lap_count=2))
    heat.start_or_pause(0.0)
    heat.capture(10.0)
    heat.did_not_finish(15.0)  # not driven: it does not bring the end nearer
    heat.start_or_pause(20.0)
    assert heat.phase is Phase.RUNNING and heat.laps_completed() == 1
    assert heat.capture(31.0) == "Lap 3: 11.000 s, counts. 2 laps done: race over."
    assert heat.phase is Phase.OVER and heat.time_left(100.0) == pytest.approx(34.0)
    result = result_of(heat)
    assert [lap.valid for lap in result.laps] == [True, False, True]
    assert result.rules.lap_count == 2
    # Its lap that was not driven does not make it a result of more laps than its race.
    assert RaceResult.from_json(result.to_json()).laps == result.laps
    # The last capture was a false finish: the race opens again.
    heat.undo_capture(32.0)
    assert heat.phase is Phase.PAUSED


def test_striking_laps_of_a_lap_count_race_keeps_it_to_its_laps() -> None:
    heat = TimekeptHeat(RaceRules(window_seconds=60.0, lap_count=2))
    heat.start_or_pause(0.0)
    heat.capture(10.0)
    heat.strike(1, 11.0)  # not a lap: the car still owes two
    heat.capture(20.0)
    assert heat.phase is Phase.RUNNING
    heat.capture(30.0)
    assert heat.phase is Phase.OVER  # laps 2 and 3 are its two
    # Lap 1 cannot count again: the race would have three laps of two.
    with pytest.raises(TimekeeperError, match="already has its 2 laps"):
        heat.strike(1, 31.0)
    assert RaceResult.from_json(result_of(heat).to_json()).rules.lap_count == 2
    # Lap 3 struck out after the end: the car owes a lap and drives it.
    said = heat.strike(3, 31.0)
    assert said == "Lap 3 struck out. The race is open again, paused: 1 more to drive."
    assert heat.phase is Phase.PAUSED
    heat.start_or_pause(40.0)
    # Putting lap 3 back while the car drives makes the two laps again: the race is over.
    assert heat.strike(3, 42.0) == "Lap 3 counts again. 2 laps done: race over."
    assert heat.phase is Phase.OVER and heat.laps_completed() == 2


def test_undo_a_capture_keeps_the_laps_resets_and_double_presses_are_refused() -> None:
    heat = TimekeptHeat(RULES)
    heat.start_or_pause(0.0)
    heat.reset(3.0)
    heat.capture(10.0)
    with pytest.raises(TimekeeperError, match="double press"):
        heat.capture(10.3)
    heat.reset(12.0)
    heat.undo_capture(13.0)  # lap 1 was not finished at 10 s after all
    assert heat.resets == 2 and heat.lap_clock(13.0) == pytest.approx(13.0)
    heat.undo_reset()
    heat.capture(20.0)
    assert [(lap.raw_seconds, lap.resets) for lap in heat.laps] == [(20.0, 1)]


def test_a_lap_not_finished_or_struck_out_never_counts() -> None:
    heat = TimekeptHeat(RULES)
    heat.start_or_pause(0.0)
    heat.capture(10.0)
    assert "paused" in heat.did_not_finish(14.0)
    assert heat.phase is Phase.PAUSED
    heat.start_or_pause(20.0)
    heat.capture(29.0)
    heat.strike(1, 30.0)  # lap 1 cut the track: the timekeeper strikes it out
    heat.end(30.0)
    result = result_of(heat)
    assert [lap.valid for lap in result.laps] == [False, False, True]
    assert result.best_lap is not None and result.best_lap.time_seconds == 9.0
    assert result.physics == PHYSICAL
    assert "counts again" in heat.strike(1, 30.0)


def test_an_automatic_timers_first_trigger_starts_the_race() -> None:
    heat = TimekeptHeat(RULES)
    heat.capture(5.0, from_timer=True)  # the car crosses the line: the race starts
    assert heat.phase is Phase.RUNNING and heat.laps == []
    heat.capture(15.0, from_timer=True)
    assert heat.laps[0].raw_seconds == 10.0
    with pytest.raises(TimekeeperError, match="start the race first"):
        TimekeptHeat(RULES).capture(1.0)


def test_a_timekept_heat_is_a_league_result_on_a_board_of_its_own() -> None:
    heat = TimekeptHeat(RULES)
    heat.start_or_pause(0.0)
    heat.capture(12.0)
    heat.end(20.0)
    with pytest.raises(TimekeeperError, match="still on"):
        TimekeptHeat(RULES).result(
            racer="A", car="c", car_hash="physical", track_name="t", track_hash="h"
        )
    result = result_of(heat)
    assert RaceResult.from_json(result.to_json()).physics == PHYSICAL  # survives a sync
    with open_league() as league:
        record_race(league, result)
        rows = leaderboard(league, Filters(), method=None)
    assert [(row.racer, row.physics, row.score) for row in rows] == [("Ada", PHYSICAL, 12.0)]


def test_a_physical_car_enters_a_night_but_only_the_timekeeper_runs_its_heat() -> None:
    from league.errors import LeagueError
    from league.nights import (
        add_entrant,
        draw_heats,
        new_night,
        pending_heats,
        run_heats,
        timekept_heats,
    )
    from sim.race.driver import reference_driver
    from sim.tracks.catalog import resolve_track

    track = resolve_track("beginner-oval")
    with open_league() as league:
        night = new_night(league, track, name="friday")
        entrant = add_entrant(league, night, "carol", " physical:blue car ")
        assert entrant.model == "physical:blue car"
        with pytest.raises(LeagueError, match="already entered"):
            add_entrant(league, night, "carol", "physical:blue car")
        with pytest.raises(LeagueError, match="is not a car name"):
            add_entrant(league, night, "dan", "physical:\u200b")
        add_entrant(league, night, "dan", "reference")
        draw_heats(league, night, seed=1)
        # The simulated heat runs headless whatever the order; the physical one waits.
        raced = run_heats(league, night, track, lambda spec, track: reference_driver(track))
        assert len(raced) == 1
        assert [heat.entrant.racer for heat in pending_heats(league, night)] == ["carol"]
        assert [heat.entrant.racer for heat in timekept_heats(league, night)] == ["carol"]
        with pytest.raises(LeagueError, match="physical cars', which a timekeeper times"):
            run_heats(league, night, track, resolve_driver=lambda spec, track: None)  # type: ignore[arg-type,return-value]

"""The race engine: continuous laps on the simulation clock, off-track penalties inside the
lap time, laps cut by the window, reversed cars turned round, determinism, live ticks."""

from __future__ import annotations

import gc
import itertools
import math
import weakref
from functools import cache

import numpy as np
import pytest

from sim.physics.car import STEP_SECONDS
from sim.physics.reference_driver import reference_lap
from sim.race.driver import reference_driver
from sim.race.engine import RaceTick, race_ticks, run_race
from sim.race.result import RaceResult
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.tracks.geometry import PointProjector, PolylineProjector
from sim.tracks.track import Track
from tests.sim.race.drivers import ReversingDriver, ScriptedDriver
from tests.sim.shapes import ring_track

SHORT = RaceRules(window_seconds=30.0)


@cache
def hairpin() -> Track:
    return resolve_track("hairpin-circuit")


@cache
def clean_race(window: float = 30.0) -> RaceResult:
    return run_race(hairpin(), RaceRules(window_seconds=window))


def test_laps_are_continuous_from_a_standing_start_and_timed_inside_the_step() -> None:
    result = clean_race()
    laps = result.laps
    assert len(laps) == 3
    # The first lap is the reference lap: a standing start on the start line.
    assert laps[0].time_seconds == reference_lap(hairpin()).lap_time
    # Flying laps are faster, and each starts where the one before ended.
    assert all(lap.time_seconds < laps[0].time_seconds for lap in laps[1:])
    for before, after in itertools.pairwise(laps):
        assert after.started_at == pytest.approx(before.started_at + before.time_seconds)
    # Crossings are interpolated: lap times are not whole numbers of 1/15 s steps.
    assert any(
        abs(lap.time_seconds / STEP_SECONDS - round(lap.time_seconds / STEP_SECONDS)) > 0.01
        for lap in laps
    )
    assert all(lap.valid and lap.offtracks == 0 and lap.penalty_seconds == 0.0 for lap in laps)
    assert result.total_offtracks == 0
    assert result.score == min(lap.time_seconds for lap in laps)
    assert result.model_name == "reference" and result.racer == "reference"
    assert result.model_hash == f"reference:{hairpin().content_hash}"


def test_a_lap_count_race_ends_as_its_last_lap_is_completed() -> None:
    timed = clean_race()
    rules = RaceRules(window_seconds=30.0, lap_count=2)
    ticks = list(race_ticks(hairpin(), rules))
    result = ticks[-1].result
    assert result is not None
    # The same two laps as the time race's first two, and not a step more.
    assert result.laps == timed.laps[:2]
    last = result.laps[-1]
    assert ticks[-1].clock == pytest.approx(last.started_at + last.time_seconds, abs=STEP_SECONDS)
    assert result.trace is not None and result.trace.statuses()[-1] == "lap_complete"
    # The window is still its time limit: a car too slow for its laps stops when it closes.
    slow = run_race(hairpin(), RaceRules(window_seconds=10.0, lap_count=3))
    assert len(slow.laps) == 1


def test_an_offtrack_costs_the_penalty_inside_the_lap_time() -> None:
    driver = ScriptedDriver(hairpin(), swerve_at=(150,))  # during lap 2
    result = run_race(hairpin(), SHORT, driver)
    clean = clean_race()
    lap = result.laps[1]
    assert (lap.offtracks, lap.penalty_seconds, lap.valid) == (1, 3.0, True)
    assert lap.time_seconds == pytest.approx(lap.raw_seconds + 3.0)
    assert lap.time_seconds > clean.laps[1].time_seconds + 3.0
    assert result.laps[0] == clean.laps[0]  # the lap before is untouched
    assert result.total_offtracks == 1
    # The trace shows the off-track, then the car held still for 3 s (45 ticks).
    trace = result.trace
    assert trace is not None
    statuses = trace.statuses()
    off = statuses.index("off_track")
    assert statuses[off + 1 : off + 46] == ["pause"] * 45
    assert statuses[off + 46] == "in_progress"
    held = slice(off + 1, off + 46)
    assert np.ptp(trace.x[held]) == 0.0 and np.ptp(trace.y[held]) == 0.0
    assert float(trace.pause[off]) == 3.0
    assert trace.t[off + 45] - trace.t[off] == pytest.approx(3.0)


def test_a_penalty_that_is_not_whole_steps_costs_exactly_its_seconds() -> None:
    rules = RaceRules(window_seconds=30.0, penalty_seconds=2.5)
    result = run_race(hairpin(), rules, ScriptedDriver(hairpin(), swerve_at=(150,)))
    lap = result.laps[1]
    assert lap.penalty_seconds == 2.5
    assert lap.time_seconds == pytest.approx(lap.raw_seconds + 2.5, abs=1e-9)


def test_a_lap_with_four_offtracks_does_not_count_unless_offtracks_are_unlimited() -> None:
    swerves = (140, 160, 180, 200)  # all in lap 2
    limited = run_race(
        hairpin(), RaceRules(window_seconds=40.0), ScriptedDriver(hairpin(), swerves)
    )
    lap = limited.laps[1]
    assert lap.offtracks == 4 and not lap.valid
    assert lap.penalty_seconds == 12.0
    assert 2 not in limited.scoring.lap_numbers
    assert limited.valid_laps == len(limited.laps) - 1

    unlimited = run_race(
        hairpin(),
        RaceRules(window_seconds=40.0, max_offtracks_per_lap=None),
        ScriptedDriver(hairpin(), swerves),
    )
    assert unlimited.laps[1].valid
    assert [lap.time_seconds for lap in unlimited.laps] == [
        lap.time_seconds for lap in limited.laps
    ]
    assert unlimited.valid_laps == len(unlimited.laps)


def test_three_offtracks_in_a_lap_still_count_by_default() -> None:
    result = run_race(
        hairpin(), RaceRules(window_seconds=40.0), ScriptedDriver(hairpin(), (140, 160, 180))
    )
    assert result.laps[1].offtracks == 3 and result.laps[1].valid


def test_a_lap_in_progress_when_the_window_closes_does_not_count() -> None:
    clean = clean_race()
    # Close the window halfway round lap 2, after an off-track in that lap.
    window = clean.laps[0].time_seconds + 3.0 + clean.laps[1].time_seconds / 2.0
    result = run_race(
        hairpin(),
        RaceRules(window_seconds=window),
        ScriptedDriver(hairpin(), swerve_at=(140,)),
    )
    assert len(result.laps) == 1
    assert result.total_offtracks == 1  # counted, though its lap never finished
    assert result.laps[0].offtracks == 0
    assert result.trace is not None
    assert result.trace.t[-1] == pytest.approx(window, abs=STEP_SECONDS)
    assert result.trace.statuses()[-1] == "time_up"


def test_a_lap_finishing_just_after_the_window_does_not_count() -> None:
    first = clean_race().laps[0].time_seconds
    assert len(run_race(hairpin(), RaceRules(window_seconds=first + 1e-3)).laps) == 1
    assert len(run_race(hairpin(), RaceRules(window_seconds=first - 1e-3)).laps) == 0


def test_a_reversed_car_is_turned_round_and_races_on() -> None:
    ring = ring_track()
    driver = ReversingDriver()
    result = run_race(ring, RaceRules(window_seconds=30.0), driver)
    assert driver.turned_round
    assert result.trace is not None
    statuses = result.trace.statuses()
    assert statuses.count("reversed") == 1
    assert "off_track" not in statuses
    # A reset, not an off-track: the lap counts, with the hold inside its time.
    assert result.laps, "the car should lap after being turned round"
    first = result.laps[0]
    assert first.valid and first.offtracks == 0 and first.penalty_seconds == 3.0
    # Counted as simapp's metrics count it: one reset, a reversal.
    assert (first.reversals, first.resets) == (1, 1)
    assert first.to_json()["reversals"] == 1
    assert all("reversals" not in lap.to_json() for lap in result.laps[1:])


def test_races_are_deterministic() -> None:
    rules = RaceRules(window_seconds=25.0)
    runs = [run_race(hairpin(), rules, ScriptedDriver(hairpin(), (150,)), seed=7) for _ in range(2)]
    first, second = (
        [(lap.time_seconds, lap.raw_seconds, lap.offtracks) for lap in run.laps] for run in runs
    )
    assert first == second
    assert runs[0].trace is not None and runs[1].trace is not None
    assert np.array_equal(runs[0].trace.x, runs[1].trace.x)
    assert runs[0].result_id != runs[1].result_id
    assert runs[0].seed == 7


def test_policy_races_are_deterministic() -> None:
    pytest.importorskip("torch")
    from sim.deepracer.action_space import discrete_grid
    from sim.deepracer.files import ModelMetadata
    from sim.training.policy import build_network
    from sim.training.policy_driver import PolicyDriver

    metadata = ModelMetadata(discrete_grid(30.0, 5, 3.0, 2), ("vector",))
    network = build_network(metadata)
    rules = RaceRules(window_seconds=20.0, penalty_seconds=0.5)
    results = [
        run_race(
            hairpin(),
            rules,
            PolicyDriver(network, metadata, name="untrained", content_hash="abc"),
        )
        for _ in range(2)
    ]
    traces = [result.trace for result in results]
    assert traces[0] is not None and traces[1] is not None
    assert np.array_equal(traces[0].x, traces[1].x)
    assert np.array_equal(traces[0].action, traces[1].action)
    assert results[0].total_offtracks == results[1].total_offtracks
    # Held rows (the start, penalties, and a window that closes during one) drive nothing.
    driven = np.isin(traces[0].statuses(), ["prepare", "pause", "time_up"], invert=True)
    assert set(traces[0].action[driven].tolist()) <= set(range(10))


def test_ticks_stream_the_race_and_the_last_one_carries_the_result() -> None:
    ticks: list[RaceTick] = list(
        race_ticks(hairpin(), SHORT, ScriptedDriver(hairpin(), (150,)), racer="Ada")
    )
    first, last = ticks[0], ticks[-1]
    assert (first.step, first.clock, first.lap, first.speed) == (0, 0.0, 1, 0.0)
    assert first.result is None and not first.finished
    assert last.finished and last.result is not None
    assert last.clock == pytest.approx(30.0)
    assert all(b.clock >= a.clock for a, b in itertools.pairwise(ticks))
    assert all(tick.result is None for tick in ticks[:-1])
    assert last.result.racer == "Ada"
    assert last.laps == last.result.laps
    # The off-track tick, then ticks counting the penalty down.
    off = next(i for i, tick in enumerate(ticks) if tick.offtrack)
    assert ticks[off].status == "off_track" and ticks[off].lap_offtracks == 1
    assert ticks[off].penalty_remaining == 3.0
    assert ticks[off + 1].status == "pause"
    assert ticks[off + 1].penalty_remaining == pytest.approx(3.0 - STEP_SECONDS)
    assert ticks[off + 1].speed == 0.0
    # Lap time keeps running through the hold.
    assert ticks[off + 1].lap_time > ticks[off].lap_time
    # The same race run to the end gives the same laps.
    fast = run_race(hairpin(), SHORT, ScriptedDriver(hairpin(), (150,)))
    assert [lap.time_seconds for lap in fast.laps] == [lap.time_seconds for lap in last.result.laps]


def test_progress_and_lap_number_follow_the_car() -> None:
    ticks = list(race_ticks(hairpin(), RaceRules(window_seconds=12.0)))
    crossing = next(i for i, tick in enumerate(ticks) if tick.laps)
    assert ticks[crossing - 1].lap == 1 and ticks[crossing].lap == 2
    assert ticks[crossing - 1].progress > 95.0
    assert ticks[crossing].progress < 5.0
    assert ticks[crossing].status == "lap_complete"
    assert ticks[crossing].lap_time < 2 * STEP_SECONDS


def test_a_full_four_minute_reference_race() -> None:
    track = hairpin()
    result = run_race(track, RaceRules(), reference_driver(track))
    flying = [lap.time_seconds for lap in result.laps[1:]]
    # The driver settles into the same lap within a lap of its flying start.
    settled = flying[1:]
    assert max(settled) - min(settled) < 0.01
    assert max(flying) - min(flying) < 0.05
    assert len(result.laps) == math.floor((240.0 - result.laps[0].time_seconds) / settled[-1]) + 1
    assert result.total_offtracks == 0
    assert result.trace is not None and len(result.trace) == 3601


def test_a_finished_race_lets_go_of_its_track_and_lookup_grids() -> None:
    """A long session races on many Track objects (each race reads its track afresh);
    the projectors and lookup grids a race builds must go with the track, not pile up."""
    track = resolve_track("beginner-oval")
    result = run_race(track, SHORT, racer="ada")
    assert result.laps
    gone = weakref.ref(track.centerline)
    del track
    gc.collect()
    assert gone() is None


def test_a_point_projector_does_not_keep_its_projector_alive() -> None:
    """No reference cycle: a dropped track's grids go at once, not at the next full
    collection (which the long-running app makes rare)."""
    projector = PolylineProjector(resolve_track("beginner-oval").center)
    fast = PointProjector.of(projector)
    assert PointProjector.of(projector) is fast  # one per projector
    gone = weakref.ref(projector)
    del projector, fast
    assert gone() is None  # without gc.collect()

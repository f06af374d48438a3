"""The car's handling against DeepRacer's own sim-traces, replayed open-loop.

Two traces: today's simulator (simapp 6.0, shipped beside these tests, not used to fit the
car) checks racer-tui's car; the shared console evaluation (simapp 4.0) checks the older
car DeepRacer drove models of metadata version 3 and 4 with.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from benchmarks.sim import calibration as bench_calibration
from sim.calibration import (
    CURVATURE_TOLERANCE,
    GAP_TARGETS,
    Calibration,
    calibrate,
    replay_runs,
    trace_runs,
)
from sim.deepracer.files import SimTraceRow, read_sim_trace
from sim.physics.car import DEEPRACER_CAR, SIMAPP4_CAR, CarSpec, Fleet, car_for_simapp_version
from tests.conftest import SHARED_DEEPRACER

SIMAPP6_TRACE = Path(__file__).parent / "data" / "deepracer-simapp6-evaluation" / "0-iteration.csv"
# racer-tui's car before the calibration: steering by its wheel centres, a quick servo.
UNCALIBRATED = dataclasses.replace(
    DEEPRACER_CAR,
    effective_wheelbase=DEEPRACER_CAR.wheelbase,
    understeer=0.0,
    steering_time_constant=0.02,
    speed_gain=1.0,
)


@pytest.fixture(scope="module")
def simapp6_rows() -> list[SimTraceRow]:
    return read_sim_trace(SIMAPP6_TRACE)


@pytest.fixture(scope="module")
def console_rows() -> list[SimTraceRow]:
    if not SHARED_DEEPRACER.is_dir():
        pytest.skip("../shared/deepracer is not beside this checkout; its console trace is absent")
    return read_sim_trace(SHARED_DEEPRACER / "console-logs/sim-trace/evaluation/0-iteration.csv")


@pytest.fixture(scope="module")
def today(simapp6_rows: list[SimTraceRow]) -> Calibration:
    return calibrate([simapp6_rows], DEEPRACER_CAR)


@pytest.fixture(scope="module")
def simapp4(console_rows: list[SimTraceRow]) -> Calibration:
    return calibrate([console_rows], SIMAPP4_CAR)


def within(value: float, reference: float, tolerance: float = 0.10) -> bool:
    return abs(value / reference - 1.0) <= tolerance


def test_a_trace_pose_is_one_row_late(console_rows: list[SimTraceRow]) -> None:
    """The convention the replay rests on: the distance between rows i and i+1 follows the
    time step of the row before (t[i] - t[i-1]) better than its own."""
    rows = [r for r in console_rows if r.episode_status == "in_progress"]
    t = np.array([r.tstamp for r in rows])
    moved = np.hypot(np.diff([r.x for r in rows]), np.diff([r.y for r in rows]))

    def roughness(step: np.ndarray) -> float:
        speed = moved[1:-1] / step
        return float(np.median(np.abs(np.diff(speed)) / speed[1:]))

    steps = np.diff(t)
    assert roughness(steps[:-2]) < 0.85 * roughness(steps[1:-1])


def test_todays_car_turns_like_deepracers_at_every_angle_and_speed(today: Calibration) -> None:
    assert len(today.curvature) >= 4  # 10-25 degrees, 1-2 m/s
    for b in today.curvature:
        assert abs(b.ratio - 1.0) <= CURVATURE_TOLERANCE, b
    assert today.curvature_within_tolerance


def test_todays_car_answers_the_steering_with_deepracers_lag(today: Calibration) -> None:
    assert 0.1 < today.lag_deepracer < 0.3
    assert within(today.lag_racer_tui, today.lag_deepracer)


def test_todays_car_reaches_deepracers_speed(today: Calibration) -> None:
    assert within(today.speed_ratio_racer_tui, today.speed_ratio_deepracer, 0.03)


def test_todays_car_replays_within_the_gap_targets(today: Calibration) -> None:
    assert today.windows > 500
    for at, target in GAP_TARGETS.items():
        assert today.gaps[at] < target
    assert today.meets_targets


def test_the_old_car_steers_slower_and_replays_the_console_trace(simapp4: Calibration) -> None:
    assert SIMAPP4_CAR.steering_time_constant > 2 * DEEPRACER_CAR.steering_time_constant
    assert within(simapp4.lag_racer_tui, simapp4.lag_deepracer)
    for at, target in GAP_TARGETS.items():
        assert simapp4.gaps[at] < target


def test_the_old_car_turns_like_the_console_trace_from_a_straight_and_at_full_lock(
    simapp4: Calibration,
) -> None:
    by_angle = {b.steering_deg: b for b in simapp4.curvature if b.speed == 1}
    assert {10, 30} <= set(by_angle)
    for angle in (10, 30):
        assert abs(by_angle[angle].ratio - 1.0) <= CURVATURE_TOLERANCE, by_angle[angle]


def test_the_old_car_turns_like_the_console_trace_at_every_angle(simapp4: Calibration) -> None:
    """After full lock a 20-degree command still turned like 30 against a plain lag; with
    the hinges' quick share, the lag and the car's pull to the left, every bin holds."""
    assert {b.steering_deg for b in simapp4.curvature} == {10, 20, 30}
    assert simapp4.curvature_within_tolerance
    assert simapp4.meets_targets


def test_the_old_car_without_its_pull_misses_the_console_trace(
    console_rows: list[SimTraceRow],
) -> None:
    """The pull is what the trace shows, not decoration: without it the replay drifts right
    of DeepRacer's path twice as far."""
    straight = dataclasses.replace(SIMAPP4_CAR, steering_offset_deg=0.0)
    without = calibrate([console_rows], straight)
    with_pull = calibrate([console_rows], SIMAPP4_CAR)
    assert without.gaps[2.0] > 1.5 * with_pull.gaps[2.0]
    assert not without.curvature_within_tolerance


def _trace(steps: list[tuple[float, float]], speed: float = 1.5) -> list[SimTraceRow]:
    """A straight drive with a steering command switched at given times: rows of (tstamp,
    steering), the car moving along x at `speed` (its poses do not matter here)."""
    rows = []
    for i, (tstamp, steer) in enumerate(steps):
        rows.append(
            SimTraceRow(
                episode=0,
                steps=i + 1,
                x=0.14 + speed * tstamp,
                y=0.0,
                yaw=0.0,
                steer=steer,
                throttle=speed,
                action=-1,
                reward=1.0,
                done=False,
                all_wheels_on_track=True,
                progress=1.0,
                closest_waypoint=0,
                track_len=10.0,
                tstamp=tstamp,
                episode_status="in_progress",
                pause_duration=0.0,
            )
        )
    return rows


def test_the_replay_applies_each_command_from_its_own_time() -> None:
    """DeepRacer's command times jitter around 1/15 s: a command sent 0.09 s into a run acts
    from then (to the physics sub-step), not from the next 15 Hz tick at 0.133 s."""
    times = [0.0, 0.09, 0.16, 0.23, 0.30]
    rows = _trace([(t, 0.0 if t < 0.09 else 30.0) for t in times])
    (run,) = trace_runs(rows, min_poses=3)
    plain = dataclasses.replace(DEEPRACER_CAR, steering_instant_share=0.0)  # a plain lag
    (replayed,) = replay_runs([run], plain)
    # By the pose at 0.16 s the wheels have turned for 0.16 - 0.09 s, 4 to 5 sub-steps; on
    # a 15 Hz grid they would have turned from 0.133 s, under 2.
    turned = replayed.steering[2] / math.radians(30.0)
    still = 1.0 - Fleet(1).dt / plain.steering_time_constant
    assert 1.0 - still**4 <= turned <= 1.0 - still**5
    assert replayed.steering[1] / math.radians(30.0) < 1.0 - still


def test_the_uncalibrated_car_turns_far_too_tight(simapp6_rows: list[SimTraceRow]) -> None:
    """The benchmark tells a wrong car from a right one: racer-tui's car before the
    calibration turned 1.6 times tighter than DeepRacer's and drifted 0.5 m in a second."""
    before = calibrate([simapp6_rows], UNCALIBRATED)
    assert all(b.ratio > 1.3 for b in before.curvature)
    assert before.gaps[1.0] > 2 * GAP_TARGETS[1.0]
    assert before.lag_racer_tui < 0.6 * before.lag_deepracer


def test_runs_pair_each_command_with_the_next_pose(simapp6_rows: list[SimTraceRow]) -> None:
    runs = trace_runs(simapp6_rows)
    first = runs[0]
    # The run's first pose is a row's, its time and command the row before's.
    index = next(
        i
        for i, row in enumerate(simapp6_rows)
        if math.isclose(row.tstamp, first.time[1]) and row.episode == simapp6_rows[0].episode
    )
    pose, command = simapp6_rows[index + 1], simapp6_rows[index]
    assert first.steering[1] == command.steer
    ahead_x = first.x[1] + 0.14 * math.cos(first.yaw[1])
    assert math.isclose(ahead_x, pose.x, abs_tol=1e-9)
    # Resets and pauses split runs: no run jumps.
    for run in runs:
        assert np.all(np.diff(run.time) > 0.0)
        assert np.hypot(np.diff(run.x), np.diff(run.y)).max() < 0.6


def test_deepracer_picks_its_car_by_the_models_metadata_version() -> None:
    assert car_for_simapp_version(5.0) is DEEPRACER_CAR
    assert car_for_simapp_version(4.0) is SIMAPP4_CAR
    assert isinstance(car_for_simapp_version(3.0), CarSpec)


def test_bench_prints_its_figures_as_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert bench_calibration.main(["--json", "--car", "default", str(SIMAPP6_TRACE)]) == 0

    report = json.loads(capsys.readouterr().out)

    assert set(report) == {"traces", "rows", "cars"}
    (car,) = report["cars"]
    assert {
        "car",
        "curvature",
        "lag_s",
        "speed_ratio",
        "gap_m",
        "targets",
        "meets_targets",
    } <= set(car)
    assert set(car["gap_m"]) == {"1s", "2s"}
    assert {"steering_deg", "speed_m_s", "deepracer_per_m", "racer_tui_per_m", "ratio"} <= set(
        car["curvature"][0]
    )
    assert car["meets_targets"] is True


def test_bench_defaults_to_the_shared_trace_and_both_cars(
    deepracer_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    del deepracer_dir  # only its presence: the bench finds the shared trace itself
    assert bench_calibration.main([]) == 0

    out = capsys.readouterr().out

    assert "0-iteration.csv" not in out  # a table, not JSON
    assert "default:" in out and "simapp4:" in out
    assert "median gap after 1 s" in out


def test_bench_names_a_missing_trace(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert bench_calibration.main([str(tmp_path / "nope.csv")]) == 2
    assert "nope.csv" in capsys.readouterr().err

"""Evaluation trials in DeepRacer's form: one lap each from the start line."""

from __future__ import annotations

import numpy as np
import pytest

from sim.deepracer.files import read_evaluation_metrics, read_sim_trace
from sim.deepracer.vocabulary import EpisodeStatus
from sim.garage.folder import ModelFolder
from sim.physics.car import STEP_HZ, STEP_SECONDS
from sim.physics.reference_driver import reference_lap
from sim.physics.simulation import TrackSimulation
from sim.race.driver import reference_driver
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import (
    EvaluationReport,
    TrialResult,
    TrialTrace,
    evaluate_model,
    evaluation_trials,
    run_trials,
    start_poses,
)
from sim.training.policy import build_network, save_policy
from sim.training.trial_resets import EVALUATION_RESETS
from tests.sim.race.drivers import HardLeft


def test_the_reference_driver_completes_every_trial_near_its_reference_lap() -> None:
    track = resolve_track("hairpin-circuit")
    results = run_trials(reference_driver(track), track, 3)
    assert [r.trial for r in results] == [1, 2, 3]
    assert all(r.status == "Lap complete" and r.progress == 100.0 for r in results)
    # Trial 1 starts exactly where the reference lap does.
    assert results[0].lap_time == pytest.approx(reference_lap(track).lap_time, abs=1e-6)
    assert all(abs(r.seconds - results[0].seconds) < 1.0 for r in results)


def test_trials_report_their_progress_about_once_a_simulated_second() -> None:
    track = resolve_track("hairpin-circuit")
    heard: list[float] = []
    results = run_trials(reference_driver(track), track, 2, on_progress=heard.append)
    seconds = max(r.seconds for r in results)
    assert len(heard) == pytest.approx(seconds, abs=2)  # one per simulated second
    assert heard[0] < 0.02 and heard == sorted(heard)
    assert 0.8 < heard[-1] <= 1.0  # the last report comes within a second of the end
    # The same trials, heard or not.
    assert run_trials(reference_driver(track), track, 2) == results


def test_only_the_first_trial_starts_exactly_on_the_line() -> None:
    poses = start_poses(5, seed=0)
    assert poses[0] == (0.0, 0.0)
    assert all(abs(offset) <= 0.03 and abs(yaw) <= 3.0 for offset, yaw in poses[1:])
    assert len(set(poses)) == 5
    assert start_poses(5, seed=0) == poses


def test_a_car_that_leaves_the_road_is_off_track_and_counted() -> None:
    track = resolve_track("hairpin-circuit")
    results = run_trials(HardLeft(), track, 2)
    assert all(r.status == "Off track" and r.lap_time is None for r in results)
    rows = evaluation_trials(results)
    assert [row.off_track_count for row in rows] == [1, 1]
    assert rows[0].completion_percentage < 100


def test_rows_follow_deepracer_evaluation_metrics() -> None:
    results = [
        TrialResult(1, "Lap complete", 100.0, 10.5),
        TrialResult(2, "Reversed", 42.123, 4.0),
        TrialResult(3, "Immobilized", 3.0, 1.0),
    ]
    rows = evaluation_trials(results)
    assert [r.trial for r in rows] == [1, 2, 3]
    assert [r.elapsed_time_in_milliseconds for r in rows] == [10500, 4000, 1000]
    assert [r.start_time for r in rows] == [0, 10500, 14500]
    assert [r.metric_time for r in rows] == [10500, 14500, 15500]
    assert (rows[1].reversed_count, rows[2].immobilized_count) == (1, 1)
    assert rows[0].lap_time_seconds == 10.5 and rows[1].lap_time_seconds is None
    report = EvaluationReport("t", tuple(results))
    assert (report.laps, report.best_lap) == (1, 10.5)


def test_evaluate_model_writes_deepracer_files(model: ModelFolder) -> None:
    save_policy(model.policy_file, build_network(model.metadata()))
    report = evaluate_model(model, trials=2)
    assert report.metrics_file is not None
    assert model.evaluation_files() == [report.metrics_file]
    trials = read_evaluation_metrics(report.metrics_file)
    assert [t.trial for t in trials] == [1, 2]
    assert [t.episode_status for t in trials] == [r.status for r in report.trials]
    # DRfC's evaluation folder, named by the metrics' 14-digit stamp.
    stamp = report.metrics_file.name.removeprefix("EvaluationMetrics-").removesuffix(".json")
    assert len(stamp) == 14 and stamp.isdigit()
    rows = read_sim_trace(model.evaluation_trace_file(stamp))
    assert [row.episode for row in rows] == sorted(row.episode for row in rows) != []
    assert {row.episode for row in rows} == {0, 1}
    assert rows[0].episode_status == "prepare"
    assert rows[-1].done
    # Two evaluations within one second still get a name each.
    again = evaluate_model(model, trials=1)
    assert again.metrics_file is not None and again.metrics_file != report.metrics_file
    assert len(model.evaluation_files()) == 2


def test_the_trace_follows_deepracers_row_timing() -> None:
    # DeepRacer's sim-trace shows a row's pose one row late: row i+1's pose is the car's
    # state at row i's tstamp, so a row shows where its command was sent from, and the
    # row that ends a trial shows where it ended. Replayed here step by step to compare.
    track = resolve_track("hairpin-circuit")
    trace = TrialTrace()
    results = run_trials(reference_driver(track), track, 1, trace=trace)
    columns = trace.columns(evaluation_trials(results), track.length)
    driver = reference_driver(track)
    sim = TrackSimulation(track, 1)
    sim.reset_cars([0], [0.0])
    driver.reset(sim)
    poses = [tuple(sim.ahead[0])]  # where the car is as each step begins, then the end
    while sim.status[0] == EpisodeStatus.IN_PROGRESS:
        action = driver.act(sim)
        sim.apply(action.steering_deg, action.speed)
        poses.append(tuple(sim.ahead[0]))
    rows = list(zip(columns.x.tolist(), columns.y.tolist(), strict=True))
    assert len(rows) == len(poses) - 1 == round(results[0].seconds * STEP_HZ + 0.5)
    assert rows[:-1] == pytest.approx(poses[:-2])  # each row where its step began
    assert rows[-1] == pytest.approx(poses[-1])  # the last where the lap ended
    assert rows[0] == pytest.approx(poses[0])  # the first at the start, as DeepRacer's
    assert columns.progress[-1] == 100.0 and columns.episode_status[-1] == "lap_complete"
    stamps = columns.tstamp
    assert np.allclose(np.diff(stamps), STEP_SECONDS)


def test_a_reset_row_shows_the_car_off_the_road_and_the_next_one_put_back() -> None:
    track = resolve_track("hairpin-circuit")
    trace = TrialTrace()
    results = run_trials(HardLeft(), track, 1, resets=EVALUATION_RESETS, trace=trace)
    assert results[0].resets  # it left the road and was put back at least once
    columns = trace.columns(evaluation_trials(results), track.length)
    off = [i for i, s in enumerate(columns.episode_status) if s == "off_track"]
    first = off[0]
    assert not columns.all_wheels_on_track[first]
    assert columns.pause_duration[first] > 0  # the clock holds for the penalty
    # The next row begins where the car was put back: on the road, by the centre line.
    assert columns.all_wheels_on_track[first + 1]
    gap = np.hypot(columns.x[first + 1] - columns.x[first], columns.y[first + 1] - columns.y[first])
    assert gap > 0.05

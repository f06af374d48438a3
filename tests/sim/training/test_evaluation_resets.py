"""Evaluation trials reset off-track cars and charge DeepRacer's penalty, as simapp does."""

from __future__ import annotations

import inspect

import pytest

from sim.physics.resets import ResetRules
from sim.race.driver import reference_driver
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import TrialResult, evaluate_model, evaluation_trials, run_trials
from sim.training.trial_resets import EVALUATION_RESETS, TRAINING_RESETS
from tests.sim.race.drivers import HardLeft, ScriptedDriver


def test_an_evaluation_off_track_costs_two_seconds_by_default() -> None:
    track = resolve_track("hairpin-circuit")
    clean = run_trials(reference_driver(track), track, 1, resets=EVALUATION_RESETS)[0]
    swerved = run_trials(
        ScriptedDriver(track, swerve_at=(60,)), track, 1, resets=EVALUATION_RESETS
    )[0]
    assert clean.resets == () and clean.penalty_seconds == 0.0
    assert swerved.status == "Lap complete"  # put back on the track, it finished the lap
    assert swerved.resets == ("Off track",)
    assert swerved.penalty_seconds == 2.0
    assert swerved.lap_time is not None and swerved.lap_time > clean.seconds + 2.0
    (row,) = evaluation_trials([swerved])
    assert (row.off_track_count, row.reset_count) == (1, 1)
    assert row.elapsed_time_in_milliseconds == round(swerved.seconds * 1000)


def test_racer_evaluations_reset_and_training_evaluations_do_not() -> None:
    assert inspect.signature(evaluate_model).parameters["resets"].default == EVALUATION_RESETS
    assert EVALUATION_RESETS.number_of_resets > 0
    assert EVALUATION_RESETS.off_track_penalty == 2.0
    assert inspect.signature(run_trials).parameters["resets"].default == TRAINING_RESETS
    track = resolve_track("hairpin-circuit")
    (trial,) = run_trials(HardLeft(), track, 1)
    assert trial.status == "Off track" and trial.resets == ()


def test_the_reset_after_number_of_resets_ends_the_trial() -> None:
    track = resolve_track("hairpin-circuit")
    trials = run_trials(HardLeft(), track, 2, resets=ResetRules(number_of_resets=2))
    for trial in trials:
        assert trial.status == "Off track"
        assert trial.resets == ("Off track", "Off track")
        assert trial.penalty_seconds == 4.0
    rows = evaluation_trials(trials)
    # simapp counts the off-track that ended the trial as well as the two resets.
    assert [(r.off_track_count, r.reset_count) for r in rows] == [(3, 3), (3, 3)]


def test_penalties_count_against_the_trial_time() -> None:
    track = resolve_track("hairpin-circuit")
    rules = ResetRules(number_of_resets=100, off_track_penalty=5.0)
    (trial,) = run_trials(HardLeft(), track, 1, max_seconds=20.0, resets=rules)
    assert trial.status == "Time Up"
    assert trial.seconds == pytest.approx(20.0, abs=5.0 + 1e-6)
    assert trial.seconds >= 20.0 - 1e-9
    assert trial.penalty_seconds == 5.0 * len(trial.resets) and len(trial.resets) >= 2


def test_a_trial_counts_its_off_tracks_as_the_console_shows_them() -> None:
    reset_then_lap = TrialResult(1, "Lap complete", 100.0, 14.0, ("Off track",) * 2, 4.0)
    ended_off = TrialResult(2, "Off track", 40.0, 9.0, ("Off track", "Reversed"), 4.0)
    assert (reset_then_lap.off_tracks, ended_off.off_tracks) == (2, 2)

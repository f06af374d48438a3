"""A job's status: what it does, how far it has got, how long it has left, how it ended."""

from __future__ import annotations

import pytest

from racer_tui.app.jobs import Job, JobState


def test_a_running_job_estimates_what_is_left_at_its_pace_so_far() -> None:
    job = Job().running("Evaluating ada", total=100, now=10.0, wall=1_000.0)
    assert job.state is JobState.RUNNING and job.fraction == 0.0
    assert job.seconds_left(now=12.0) is None  # no pace yet
    job = job.advanced(25)
    assert job.fraction == 0.25
    assert job.seconds_left(now=14.0) == pytest.approx(12.0)  # 4 s for a quarter


def test_a_job_without_a_known_end_has_no_fraction_and_no_eta() -> None:
    job = Job().running("Syncing", total=None, now=0.0, wall=0.0).advanced(40)
    assert job.fraction is None and job.seconds_left(now=5.0) is None


def test_how_a_job_ended_replaces_its_progress() -> None:
    running = Job().running("Evaluating ada", total=100, now=0.0, wall=0.0).advanced(60)
    done = running.finished("3 of 3 trials completed the lap", wall=50.0)
    assert done.state is JobState.DONE and done.fraction == 1.0 and done.at == 50.0
    assert done.seconds_left(now=60.0) is None
    failed = running.failed("The policy cannot be read.", "Press ctrl+e.", wall=51.0)
    assert failed.state is JobState.FAILED and failed.fix == "Press ctrl+e."
    assert failed.outcome == "The policy cannot be read."
    stopped = running.stopped(wall=52.0)
    assert stopped.state is JobState.STOPPED and stopped.seconds_left(now=60.0) is None
    # Running again starts afresh: nothing of the last run's end remains.
    again = failed.running("Evaluating ada", total=100, now=70.0, wall=70.0)
    assert again.outcome == "" and again.fix == "" and again.done == 0.0

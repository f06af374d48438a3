"""The training child process, for real: its JSON stream, stopping, killing and resuming.

Each test starts `python -m sim.training.worker` with a tiny budget (8 cars, small
rollouts), and waits for events rather than for time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from sim.deepracer.files import read_sim_trace, read_training_metrics
from sim.foundation.remedies import Fix
from sim.garage.folder import ModelFolder, ModelStatus
from sim.training import events
from sim.training.checkpoint import LATEST
from sim.training.launcher import TrainingProcess
from sim.training.policy import load_policy
from sim.training.worker import StopFlag

pytestmark = pytest.mark.slow

TINY = [
    "--cars", "8",
    "--min-samples", "64",
    "--max-samples", "256",
    "--evaluation-seconds", "0",
    "--checkpoint-seconds", "0",
    "--seed", "3",
]  # fmt: skip


def _until(stream: Iterator[events.Event], kind: type[events.Event]) -> list[events.Event]:
    seen: list[events.Event] = []
    for event in stream:
        seen.append(event)
        if isinstance(event, kind):
            return seen
    raise AssertionError(f"the stream ended before a {kind.__name__} event: {seen[-1:]}")


def test_a_short_run_streams_every_kind_of_event_and_leaves_deepracer_files(
    model: ModelFolder,
) -> None:
    process = TrainingProcess.start(model.name, minutes=0.05, extra=TINY)
    stream = list(process.events())
    assert process.wait() == 0
    kinds = [events.type_of(e) for e in stream]
    assert kinds[0] == "started" and kinds[-1] == "finished"
    assert {"update", "evaluation", "checkpoint", "system"} <= set(kinds)
    started = stream[0]
    assert isinstance(started, events.Started)
    assert (started.model, started.cars, started.resumed_from) == ("tiny", 8, "scratch")
    updates = [e for e in stream if isinstance(e, events.Update)]
    assert all(u.steps_per_second > 0 and u.total_steps > 0 for u in updates)
    assert [u.iteration for u in updates] == list(range(1, len(updates) + 1))

    metrics = read_training_metrics(model.training_metrics_file)
    phases = {row.phase for row in metrics.episodes}
    assert phases <= {"training", "evaluation"} and "evaluation" in phases
    traces = sorted(model.training_trace_dir.glob("*-iteration.csv"))
    assert traces and read_sim_trace(traces[0])
    load_policy(model.policy_file, model.metadata())
    state = json.loads(model.training_state_file.read_text())
    assert state["state"] == "finished" and state["steps"] == updates[-1].total_steps
    assert model.status() == ModelStatus.TRAINED


def test_sigterm_stops_the_run_with_a_checkpoint(model: ModelFolder) -> None:
    process = TrainingProcess.start(model.name, minutes=10, extra=TINY)
    stream = process.events()
    _until(stream, events.Update)
    process.stop()
    rest = list(stream)
    assert process.wait() == 0
    ended = rest[-1]
    assert isinstance(ended, events.Ended) and ended.kind == "stopped"
    assert ended.message == "training was stopped on request"  # words, not a signal name
    assert (model.checkpoints_dir / LATEST).is_file()
    assert json.loads(model.training_state_file.read_text())["state"] == "stopped"
    assert model.has_policy() and not model.is_training()


def test_after_sigkill_the_folder_is_consistent_and_training_resumes(
    model: ModelFolder,
) -> None:
    first = TrainingProcess.start(model.name, minutes=10, extra=TINY)
    stream = first.events()
    checkpointed = _until(stream, events.Checkpoint)[-1]
    assert isinstance(checkpointed, events.Checkpoint)
    first.kill()
    ended = list(stream)[-1]
    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "SIGKILL" in ended.message

    # Every file parses; the state file still says "running", but nobody is.
    read_training_metrics(model.training_metrics_file)
    assert json.loads(model.training_state_file.read_text())["state"] == "running"
    assert not model.is_training() and model.status() != ModelStatus.TRAINING

    second = TrainingProcess.start(model.name, minutes=10, extra=TINY)
    stream = second.events()
    started = _until(stream, events.Started)[-1]
    assert isinstance(started, events.Started)
    assert started.resumed_from == "checkpoint"
    assert started.total_steps >= checkpointed.total_steps
    assert not list(model.path.rglob(".*.tmp"))  # a killed write's temporary file is gone
    update = _until(stream, events.Update)[-1]
    assert isinstance(update, events.Update) and update.total_steps > started.total_steps
    second.stop()
    assert list(stream)[-1].kind == "stopped"  # type: ignore[union-attr]
    second.wait()


def test_an_unknown_model_fails_with_one_sentence() -> None:
    process = TrainingProcess.start("no-such-model", minutes=1)
    stream = list(process.events())
    assert process.wait() == 2
    assert len(stream) == 1
    ended = stream[0]
    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "no model named 'no-such-model'" in ended.message


def test_a_model_whose_track_is_gone_fails_with_the_remedy_apart(model: ModelFolder) -> None:
    """The command line's sentence names a command; the app needs the problem and the
    remedy apart to offer its own key instead (`racer_tui.app.words`)."""
    params = model.training_params_file
    params.write_text(params.read_text().replace("reinvent_base", "zzqxw"))
    process = TrainingProcess.start(model.name, minutes=1, extra=TINY)
    (ended,) = list(process.events())
    assert process.wait() != 0
    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "`racer-tui tracks list`" in ended.message
    assert ended.problem == (
        "model 'tiny' trains on track 'zzqxw': there is no track named 'zzqxw'"
    )
    assert ended.remedy is Fix.CHOOSE_TRACK


def test_the_stop_flag_notices_a_vanished_parent() -> None:
    assert not StopFlag(os.getppid())()
    orphan = StopFlag(parent_pid=os.getpid())  # "our parent" is not our parent: it is gone
    assert orphan()
    assert orphan.reason == "the parent process exited"


def test_a_reward_function_that_fails_is_reported_in_the_racers_words(
    model: ModelFolder,
) -> None:
    model.reward_file.write_text(
        "def reward_function(params):\n"
        "    if params['steps'] > 5:\n"
        "        raise ValueError('too far')\n"
        "    return 1.0\n",
        encoding="utf-8",
    )
    process = TrainingProcess.start(model.name, minutes=1, extra=TINY)
    ended = list(process.events())[-1]
    process.wait()

    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "too far" in ended.message and "reward_function" in ended.message
    assert "RewardFunctionError" not in ended.message  # no internal class names


def test_a_reward_function_that_hangs_fails_the_training_at_its_line(
    model: ModelFolder,
) -> None:
    model.reward_file.write_text(
        "def reward_function(params):\n"
        "    while params['steps'] > 5:\n"
        "        pass\n"
        "    return 1.0\n",
        encoding="utf-8",
    )
    process = TrainingProcess.start(model.name, minutes=1, extra=[*TINY, "--reward-seconds", "0.5"])
    ended = list(process.events())[-1]
    process.wait()
    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "line 2" in ended.message and "did not return within 0.5 s" in ended.message
    assert not model.is_training()


def test_a_child_that_runs_past_its_budget_is_stopped_by_its_parent(tmp_path: Path) -> None:
    # A child that ignores SIGTERM and never ends: its parent stops, then kills it.
    stubborn = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(600)",
        ],
        stdout=subprocess.PIPE,
    )
    process = TrainingProcess(stubborn, (tmp_path / "stderr").open("w+b"))
    process.enforce_budget(0.2, grace_seconds=0.2, kill_after=0.5)
    ended = list(process.events())[-1]
    assert isinstance(ended, events.Ended) and ended.kind == "stopped"
    assert "ran well past its 0.00333333-minute budget" in ended.message
    assert stubborn.poll() is not None


def test_two_trainings_of_one_model_started_together_never_both_run(
    model: ModelFolder,
) -> None:
    first = TrainingProcess.start(model.name, minutes=0.05, extra=TINY)
    second = TrainingProcess.start(model.name, minutes=0.05, extra=TINY)
    endings = []
    for process in (first, second):
        ended = list(process.events())[-1]
        process.wait()
        assert isinstance(ended, events.Ended)
        endings.append(ended)
    kinds = sorted(ended.kind for ended in endings)
    assert kinds == ["failed", "finished"], endings
    (refused,) = [ended for ended in endings if ended.kind == "failed"]
    assert "is already training in another process" in refused.message

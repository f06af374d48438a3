"""`racer-tui train` and `racer-tui evaluate` as a racer uses them."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from racer_tui.cli.main import main
from sim.deepracer.files import read_evaluation_metrics
from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from sim.training import events
from sim.training.policy import build_network, save_policy
from sim.training.run_history import read_history
from tests.test_architecture import _import_report


@pytest.fixture
def model() -> ModelFolder:
    return new_model("tiny")


@pytest.fixture
def trained(model: ModelFolder) -> ModelFolder:
    """A model with (untrained) policy weights: enough to evaluate."""
    save_policy(model.policy_file, build_network(model.metadata()))
    return model


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_train_json_streams_valid_events_from_start_to_finish(
    capsys: pytest.CaptureFixture[str], model: ModelFolder
) -> None:
    code, out, err = run_cli(capsys, "train", "tiny", "--minutes", "0.02", "--json")
    assert code == 0, err
    stream = [events.decode(line) for line in out.splitlines()]
    assert events.type_of(stream[0]) == "started"
    assert events.type_of(stream[-1]) == "finished"
    assert any(isinstance(e, events.Update) for e in stream)
    assert model.has_policy()
    # The same events are in the model's training log, which the app follows.
    logged = model.training_log.read_text().splitlines()
    assert [events.decode(line) for line in logged] == stream
    # Its updates and system readings are in the model's run history, for later charts.
    kept = [e for e in stream if isinstance(e, events.Update | events.System)]
    assert kept and read_history(model.training_history) == kept


@pytest.mark.slow
def test_ctrl_c_stops_the_training_cleanly(model: ModelFolder) -> None:
    command = [
        sys.executable,
        "-m",
        "racer_tui.cli.main",
        "train",
        "tiny",
        "--minutes",
        "5",
        "--json",
    ]
    cli = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=dict(os.environ))
    assert cli.stdout is not None
    for line in cli.stdout:
        if isinstance(events.decode(line), events.Update):
            break
    cli.send_signal(signal.SIGINT)  # what Ctrl+C does to the foreground command
    rest = [events.decode(line) for line in cli.stdout]
    assert cli.wait(timeout=60) == 0
    ended = rest[-1]
    assert isinstance(ended, events.Ended) and ended.kind == "stopped"
    assert (model.checkpoints_dir / "latest.safetensors").is_file()
    assert not model.is_training()


@pytest.mark.slow
def test_a_killed_train_command_leaves_no_training_behind(model: ModelFolder) -> None:
    # A slow reward (under its time limit): the child is deep in a rollout, far from the
    # moments it looks for its parent, so only dying with its parent can end it in time.
    model.reward_file.write_text(
        "import time\ndef reward_function(params):\n    time.sleep(0.2)\n    return 1.0\n",
        encoding="utf-8",
    )
    command = [
        sys.executable,
        "-m",
        "racer_tui.cli.main",
        "train",
        "tiny",
        "--minutes",
        "5",
        "--json",
    ]
    cli = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=dict(os.environ))
    assert cli.stdout is not None
    child = 0
    for line in cli.stdout:
        event = events.decode(line)
        if isinstance(event, events.Started):
            child = event.pid
            break
    assert child
    cli.kill()  # SIGKILL: the command gets no chance to stop its child itself
    cli.wait(timeout=30)
    for _ in range(100):
        if not _alive(child):
            break
        time.sleep(0.1)
    assert not _alive(child), "the training child outlived its command"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # A zombie (dead, not yet reaped by init) counts as gone.
    with open(f"/proc/{pid}/stat", encoding="ascii") as stat:
        return stat.read().split(") ")[-1][:1] != "Z"


def test_evaluate_prints_the_console_table_and_writes_deepracer_metrics(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder
) -> None:
    code, out, _ = run_cli(capsys, "evaluate", "tiny", "--trials", "3")
    assert code == 0
    assert "Trial" in out and "% track completed" in out and "Status" in out
    assert "reinvent_base" in out
    (metrics,) = trained.evaluation_files()
    assert [t.trial for t in read_evaluation_metrics(metrics)] == [1, 2, 3]


def test_evaluate_json_on_another_track(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder
) -> None:
    code, out, _ = run_cli(capsys, "evaluate", "tiny", "--track", "beginner-oval", "--json")
    assert code == 0
    report = json.loads(out)
    assert report["track"] == "beginner-oval" and len(report["trials"]) == 5
    assert set(report["trials"][0]) == {
        "trial",
        "time_seconds",
        "completion_percentage",
        "status",
        "off_tracks",
        "penalty_seconds",
    }


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("train", "ghost"), "no model named 'ghost'"),
        (("evaluate", "ghost"), "no model named 'ghost'"),
        (("train", "tiny", "--minutes", "0"), "--minutes must be more than 0"),
        (("evaluate", "tiny", "--trials", "0"), "--trials must be between 1 and 100"),
        (("evaluate", "tiny"), "has no trained policy yet"),
        (
            ("train", "tiny", "--opponent", "reference"),
            "--opponent: a model that races among objects needs a camera or a lidar",
        ),
    ],
)
def test_user_errors_are_one_sentence_and_exit_code_2(
    capsys: pytest.CaptureFixture[str], model: ModelFolder, args: tuple[str, ...], message: str
) -> None:
    code, _out, err = run_cli(capsys, *args)
    assert code == 2
    assert err.startswith("racer-tui: ") and message in err
    assert len(err.strip().splitlines()) == 1


def test_a_model_training_elsewhere_keeps_its_log(
    capsys: pytest.CaptureFixture[str], model: ModelFolder
) -> None:
    # Another process holds the training lock but has not written its state yet: a second
    # `train` must not empty the log the first one (and the app) are writing.
    import fcntl

    model.training_log.write_text('{"type": "started"}\n')
    with model.training_lock_file.open("a+b") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        code, _out, err = run_cli(capsys, "train", "tiny", "--minutes", "0.02")
    assert code == 2 and "already training in another process" in err
    assert model.training_log.read_text() == '{"type": "started"}\n'


def test_the_commands_do_not_import_torch_in_the_cli_process() -> None:
    report = _import_report(["racer_tui.cli.train_commands", "sim.training.launcher"])
    assert all(heavy == [] for heavy in report.values()), report

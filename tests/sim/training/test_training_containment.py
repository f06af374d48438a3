"""A training always returns and leaves no process behind, whatever its reward function
does: the launcher kills the training's whole session once the training process exits, and
a reward that starts a process fails the run in one sentence naming its line."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import tempfile
import textwrap
import uuid

import psutil
import pytest

from racer_tui.cli.main import main
from sim.garage.options import new_model
from sim.training import events
from sim.training.launcher import AsyncTrainingProcess, TrainingProcess
from tests.leftover_processes import processes_with

pytestmark = [
    pytest.mark.skipif(
        not sys.platform.startswith("linux"), reason="process sessions and subreapers are Linux's"
    ),
    pytest.mark.usefixtures("no_leftover_processes"),
]


# A training of 8 cars that updates after 64 to 256 steps and skips its evaluations.
SMALL_FLEET = [
    "--cars",
    "8",
    "--min-samples",
    "64",
    "--max-samples",
    "256",
    "--evaluation-seconds",
    "0",
    "--checkpoint-seconds",
    "0",
]


def descendants() -> set[int]:
    """This process's descendants now (a test session may hold some of its own, such as
    multiprocessing's resource tracker: compare before and after)."""
    return {child.pid for child in psutil.Process().children(recursive=True)}


def _ended_line() -> str:
    ended = events.Ended(
        elapsed=1.0,
        kind="finished",
        message="the time limit was reached",
        total_steps=1,
        episodes=1,
        best_progress=0.0,
        best_lap=None,
    )
    return events.encode(ended)


def _orphaning_child(marker: str) -> list[str]:
    """A stand-in for the training process: it leaves an endless grandchild that holds its
    stdout (the event pipe), says it finished, and exits."""
    script = textwrap.dedent(
        f"""\
        import subprocess, sys
        subprocess.Popen([sys.executable, "-c", "while True: pass", {marker!r}])
        print({_ended_line()!r}, flush=True)
        """
    )
    return [sys.executable, "-c", script]


def test_an_orphan_holding_the_event_pipe_does_not_hang_the_launcher() -> None:
    marker = f"orphan-{uuid.uuid4()}"
    stderr = tempfile.TemporaryFile()  # noqa: SIM115 - the launcher closes it
    popen = subprocess.Popen(
        _orphaning_child(marker),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=stderr,
        start_new_session=True,
    )
    process = TrainingProcess(popen, stderr)
    stream = list(process.events())  # returns: the orphan went with the session
    assert isinstance(stream[-1], events.Ended) and stream[-1].kind == "finished"
    assert processes_with(marker) == []


@pytest.mark.asyncio
async def test_the_async_launcher_ends_the_session_too() -> None:
    marker = f"orphan-{uuid.uuid4()}"
    stderr = tempfile.TemporaryFile()  # noqa: SIM115 - the launcher closes it
    command = _orphaning_child(marker)
    child = await asyncio.create_subprocess_exec(
        *command,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=stderr,
        start_new_session=True,
    )
    process = AsyncTrainingProcess(child, stderr)
    stream = [event async for event in process.events()]
    assert isinstance(stream[-1], events.Ended)
    assert processes_with(marker) == []


@pytest.mark.slow
def test_a_reward_that_starts_a_process_fails_the_training_and_leaves_none(
    capsys: pytest.CaptureFixture[str],
) -> None:
    model = new_model("forks")
    marker = f"1000.{uuid.uuid4().int % 10**9}"
    model.reward_file.write_text(
        "import subprocess\n"
        "def reward_function(params):\n"
        f"    subprocess.Popen(['sleep', '{marker}'])\n"
        "    return 1.0\n"
    )
    before = descendants()
    code = main(["train", "forks", "--minutes", "0.02", "--json"])
    err = capsys.readouterr().err
    assert code == 2
    assert "reward_function.py line 3: reward_function starts a process" in err
    assert processes_with(marker) == []
    assert descendants() <= before


@pytest.mark.slow
def test_a_reward_file_that_allocates_without_bound_fails_as_it_loads(
    capsys: pytest.CaptureFixture[str],
) -> None:
    model = new_model("hoards")
    model.reward_file.write_text(
        "kept = bytearray(8 * 10**9)\ndef reward_function(params):\n    return 1.0\n"
    )
    code = main(["train", "hoards", "--minutes", "0.02", "--reward-memory-mb", "64"])
    err = capsys.readouterr().err
    assert code == 2
    assert "reward_function.py line 1: loading the file used more than 64 MB of memory" in err


@pytest.mark.slow
def test_a_reward_that_allocates_in_a_simulation_process_fails_in_a_sentence(
    capsys: pytest.CaptureFixture[str],
) -> None:
    model = new_model("grows")
    model.reward_file.write_text(
        "def reward_function(params):\n    return float(len(bytearray(8 * 10**9)))\n"
    )
    command = ["train", "grows", "--minutes", "0.02", "--processes", "2"]
    before = descendants()
    code = main([*command, "--reward-memory-mb", "256"])
    err = capsys.readouterr().err
    assert code == 2
    assert "reward_function.py line 2: reward_function used more than 256 MB of memory" in err
    assert descendants() <= before


@pytest.mark.slow
def test_an_endless_child_that_gets_past_the_guard_ends_with_the_training(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from tests.sim.test_reward_containment import PAST_THE_GUARD, processes_marked

    marker = str(uuid.uuid4())
    monkeypatch.setenv("REWARD_CONTAINMENT_MARKER", marker)
    model = new_model("spins")
    model.reward_file.write_text(PAST_THE_GUARD)
    before = descendants()
    # A small fleet and batch: the spinning child takes a core from the first step, and a
    # default training's first 2,048 steps then take half a minute on two cores.
    training = TrainingProcess.start("spins", minutes=0.02, extra=SMALL_FLEET)
    ended = list(training.events())[-1]
    assert training.wait() == 0  # the child was not seen: the training runs its course
    assert isinstance(ended, events.Ended) and ended.kind == "finished"
    assert (model.path / "spinning").exists()  # the child did run
    assert processes_marked(marker) == []
    assert descendants() <= before

"""The launcher, without torch in this process: a child that fails says why."""

from __future__ import annotations

import pytest

from sim.training import events
from sim.training.launcher import AsyncTrainingProcess, failure_from_stderr, worker_command


def test_the_worker_command_uses_this_interpreter_and_names_the_parent() -> None:
    command = worker_command("fast", 2.5, ["--cars", "8"])
    assert command[1:4] == ["-m", "sim.training.worker", "fast"]
    assert "--parent-pid" in command and command[-2:] == ["--cars", "8"]
    assert command[command.index("--minutes") + 1] == "2.5"


@pytest.mark.asyncio
async def test_the_async_launcher_streams_the_childs_last_word() -> None:
    process = await AsyncTrainingProcess.start("no-such-model", minutes=1)
    stream = [event async for event in process.events()]
    assert await process.wait() == 2
    (ended,) = stream
    assert isinstance(ended, events.Ended) and ended.kind == "failed"
    assert "no model named 'no-such-model'" in ended.message


def test_a_child_that_died_silently_gets_a_failed_ending() -> None:
    ended = failure_from_stderr(-9, "")
    assert ended.kind == "failed" and "SIGKILL" in ended.message
    ended = failure_from_stderr(1, "Traceback...\nMemoryError: out of memory\n")
    assert ended.message.endswith("MemoryError: out of memory")

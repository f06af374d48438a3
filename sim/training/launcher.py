"""Start the training child and read its JSON event stream (no torch in this process).

The child runs `python -m sim.training.worker` with stdin from /dev/null and in a new
session, so a Ctrl+C in the terminal reaches only the parent, which then stops the child
on purpose: `stop()` sends SIGTERM, and the child saves a checkpoint and writes its last
event before exiting. The child watches this process's pid, so it also stops if the parent
dies without a word.

`TrainingProcess` is for synchronous callers (the CLI); `AsyncTrainingProcess` is for an
asyncio event loop (the TUI), as Textual needs: never `multiprocessing` inside the app.
Lines that are not valid events (a stray print from a library) are skipped, not fatal.

The child's session is killed as a whole (SIGKILL to its process group) as soon as the
child has exited, however it ended: nothing it started (its simulation processes, or a
process a racer's reward function managed to leave) outlives the training, and nothing can
hold the event pipe open after it, so reading the events always ends.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import os
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import AsyncIterator, Iterator, Sequence
from typing import IO

from sim.reward.sandbox import kill_session, wait_for_exit
from sim.training import events

STOP_TIMEOUT = 60.0  # seconds to wait for a checkpoint after SIGTERM before SIGKILL


def budget_grace(budget_seconds: float) -> float:
    """How long past its time budget a child may run before its parent stops it: start-up
    (importing torch), the last update and the final checkpoint fit in this."""
    return 60.0 + 0.1 * budget_seconds


STDERR_TAIL = 2000


def worker_command(
    model: str, minutes: float | None = None, extra: Sequence[str] = ()
) -> list[str]:
    """The child's command line (the same interpreter as this process)."""
    command = [sys.executable, "-m", "sim.training.worker", model]
    if "--parent-pid" not in extra:  # the app names its own: no parent, so it may outlive it
        command += ["--parent-pid", str(os.getpid())]
    if minutes is not None:
        command += ["--minutes", repr(float(minutes))]
    return command + list(extra)


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONUNBUFFERED"] = "1"
    env.setdefault("OMP_NUM_THREADS", "1")  # tiny networks: one BLAS thread is fastest
    return env


def _decode(line: bytes | str) -> events.Event | None:
    text = line.strip()
    if not text:
        return None
    try:
        return events.decode(text)
    except events.EventError:
        return None


def failure_from_stderr(
    returncode: int | None, stderr_tail: str, *, elapsed: float = 0.0
) -> events.Ended:
    """The ending for a child that died without writing its last event, `elapsed` seconds
    into its run as its last event said (the app uses it too)."""
    last = stderr_tail.strip().splitlines()[-1] if stderr_tail.strip() else ""
    if returncode is None:  # not our child: its exit status cannot be known
        reason = "the training process ended without writing how (it was killed or crashed)"
    else:
        reason = f"the training process exited with code {returncode}"
    if returncode is not None and returncode < 0:
        with contextlib.suppress(ValueError):
            reason = f"the training process was killed by {signal.Signals(-returncode).name}"
    return events.Ended(
        elapsed=elapsed,
        kind="failed",
        message=f"{reason}: {last}" if last else reason,
        total_steps=0,
        episodes=0,
        best_progress=0.0,
        best_lap=None,
    )


def overran(ended: events.Ended, budget_seconds: float) -> events.Ended:
    """The end of a run its parent had to stop, said as it happened."""
    return dataclasses.replace(
        ended,
        kind="stopped",
        message=(
            f"training ran well past its {budget_seconds / 60:g}-minute budget without "
            "stopping, so it was stopped; its last checkpoint is kept"
        ),
    )


def _end_session_when_done(pid: int) -> None:
    """Wait (without reaping) for the child to exit, then kill its session: whatever still
    holds the event pipe goes with it."""
    wait_for_exit(pid)
    kill_session(pid)


def _settle(future: asyncio.Future[None]) -> None:
    if not future.done():
        future.set_result(None)


def _tail(handle: IO[bytes]) -> str:
    handle.seek(0, os.SEEK_END)
    size = handle.tell()
    handle.seek(max(0, size - STDERR_TAIL))
    return handle.read().decode("utf-8", "replace")


class TrainingProcess:
    """A running training child, read synchronously: `for event in process.events()`."""

    def __init__(self, popen: subprocess.Popen[bytes], stderr: IO[bytes]) -> None:
        self._popen = popen
        self._stderr = stderr
        self.ended: events.Ended | None = None
        self.overran: float | None = None  # the budget it ran past, when it was stopped
        self._timers: list[threading.Timer] = []
        self._session_ender = threading.Thread(
            target=_end_session_when_done, args=(popen.pid,), name="training-session", daemon=True
        )
        self._session_ender.start()

    @classmethod
    def start(
        cls,
        model: str,
        minutes: float | None = None,
        extra: Sequence[str] = (),
        *,
        budget_seconds: float | None = None,
    ) -> TrainingProcess:
        """Start the child; with `budget_seconds`, this process stops it (and kills it if
        it does not stop) once it runs `budget_grace` past its budget, whatever the child
        is doing: its own clock cannot be trusted to run while it hangs."""
        stderr = tempfile.TemporaryFile()  # noqa: SIM115 - lives as long as the child
        popen = subprocess.Popen(
            worker_command(model, minutes, extra),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=stderr,
            start_new_session=True,
            env=_child_env(),
        )
        process = cls(popen, stderr)
        if budget_seconds is not None:
            process.enforce_budget(budget_seconds)
        return process

    def enforce_budget(
        self,
        budget_seconds: float,
        grace_seconds: float | None = None,
        kill_after: float = STOP_TIMEOUT,
    ) -> None:
        """Stop the child `grace_seconds` (default `budget_grace`) after its budget, and
        kill it `kill_after` seconds later if it has not stopped."""

        def over_budget() -> None:
            if self._popen.poll() is None:
                self.overran = budget_seconds
                self.stop()
                kill = threading.Timer(kill_after, self.kill)
                kill.daemon = True
                self._timers.append(kill)
                kill.start()

        grace = budget_grace(budget_seconds) if grace_seconds is None else grace_seconds
        timer = threading.Timer(budget_seconds + grace, over_budget)
        timer.daemon = True
        self._timers.append(timer)
        timer.start()

    @property
    def pid(self) -> int:
        return self._popen.pid

    @property
    def returncode(self) -> int | None:
        return self._popen.poll()

    def events(self) -> Iterator[events.Event]:
        """Every event until the child's last one (synthesised if it died silently)."""
        assert self._popen.stdout is not None
        elapsed = 0.0
        for line in self._popen.stdout:
            event = _decode(line)
            if event is None:
                continue
            elapsed = max(elapsed, event.elapsed)
            if isinstance(event, events.Ended):
                if self.overran is not None:
                    event = overran(event, self.overran)
                self.ended = event
            yield event
        self._session_ender.join()  # the child has exited and its session is ended
        code = self._popen.wait()
        for timer in self._timers:
            timer.cancel()
        if self.ended is None:
            self.ended = failure_from_stderr(code, _tail(self._stderr), elapsed=elapsed)
            if self.overran is not None:
                self.ended = overran(self.ended, self.overran)
            yield self.ended
        self._stderr.close()

    def stop(self) -> None:
        """Ask the child to stop (SIGTERM): it saves a checkpoint and writes its last event.
        Keep reading `events()` to receive it; the child exits after."""
        if self._popen.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                self._popen.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        """SIGKILL: the folder stays consistent, the work since the last checkpoint is lost."""
        if self._popen.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                self._popen.kill()

    def wait(self, timeout: float = STOP_TIMEOUT) -> int:
        """Wait for the child to exit; SIGKILL it after `timeout` seconds."""
        try:
            return self._popen.wait(timeout)
        except subprocess.TimeoutExpired:
            self._popen.kill()
            return self._popen.wait()


class AsyncTrainingProcess:
    """The same for asyncio: `async for event in process.events()`."""

    def __init__(self, process: asyncio.subprocess.Process, stderr: IO[bytes]) -> None:
        self._process = process
        self._stderr = stderr
        self.ended: events.Ended | None = None
        # Not `process.wait()`: asyncio's waits for the child's pipes to close too, which
        # is what an orphan holding them prevents. Nor `asyncio.to_thread`: the loop waits
        # for its executor's threads as it closes, and an app that leaves a training running
        # would then wait for the training.
        loop = asyncio.get_running_loop()
        self._session_ended: asyncio.Future[None] = loop.create_future()

        def end_session() -> None:
            _end_session_when_done(process.pid)
            with contextlib.suppress(RuntimeError):  # the loop has closed: nobody waits
                loop.call_soon_threadsafe(_settle, self._session_ended)

        threading.Thread(target=end_session, name="training-session", daemon=True).start()

    @classmethod
    async def start(
        cls, model: str, minutes: float | None = None, extra: Sequence[str] = ()
    ) -> AsyncTrainingProcess:
        stderr = tempfile.TemporaryFile()  # noqa: SIM115 - lives as long as the child
        process = await asyncio.create_subprocess_exec(
            *worker_command(model, minutes, extra),
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.PIPE,
            stderr=stderr,
            start_new_session=True,
            env=_child_env(),
        )
        return cls(process, stderr)

    @property
    def pid(self) -> int:
        return self._process.pid

    @property
    def returncode(self) -> int | None:
        return self._process.returncode

    async def events(self) -> AsyncIterator[events.Event]:
        assert self._process.stdout is not None
        elapsed = 0.0
        async for line in self._process.stdout:
            event = _decode(line)
            if event is None:
                continue
            elapsed = max(elapsed, event.elapsed)
            if isinstance(event, events.Ended):
                self.ended = event
            yield event
        await self._session_ended  # the child has exited and its session is ended
        code = await self._process.wait()
        if self.ended is None:
            self.ended = failure_from_stderr(code, _tail(self._stderr), elapsed=elapsed)
            yield self.ended
        self._stderr.close()

    def stop(self) -> None:
        """Ask the child to stop (SIGTERM); its last event still arrives through `events()`,
        which should keep being read (a child blocked on a full pipe cannot finish)."""
        if self._process.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                self._process.send_signal(signal.SIGTERM)

    async def wait(self, timeout: float = STOP_TIMEOUT) -> int:
        """Wait for the child to exit; SIGKILL it after `timeout` seconds."""
        try:
            return await asyncio.wait_for(self._process.wait(), timeout)
        except TimeoutError:
            self._process.kill()
            return await self._process.wait()

"""The training child process: `python -m sim.training.worker MODEL [--minutes M]`.

It trains one garage model and writes one JSON event per line on stdout (see
`sim.training.events`); the last line is `finished`, `stopped` or `failed`. It stops
cleanly, saving a checkpoint, on SIGTERM, SIGINT or SIGHUP, when its parent process
exits (stdin is /dev/null, so the parent's pid is watched instead), or when stdout is
closed. A user error (unknown model, bad files, another training of the same model
running) is a `failed` event with one sentence and exit code 2.

It runs the racer's reward function (in its own part of the fleet, and in the simulation
processes it starts), so it contains it (sim.reward.sandbox): the events go out on a
descriptor of their own, and the process's stdout, where the function's prints land, is
the training's stderr log, never the pipe its parent reads; it is the subreaper of every
process under it and ends them all before it exits, so nothing the function might leave
running holds that pipe or a core.
"""

from __future__ import annotations

import argparse
import fcntl
import os
import signal
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import TextIO

from sim.foundation.parent import die_with_parent
from sim.foundation.remedies import RemedyError
from sim.garage.folder import ModelError, open_model
from sim.reward import guard as reward_guard
from sim.reward import sandbox as reward_sandbox
from sim.reward.errors import RewardFunctionError
from sim.reward.limit import DEFAULT_SECONDS as DEFAULT_REWARD_SECONDS
from sim.reward.sandbox import DEFAULT_MEMORY_MB
from sim.training import events
from sim.training.allocator import keep_freed_memory
from sim.training.errors import describe_failure, failure_remedy

EXIT_FAILED = 1
EXIT_USER_ERROR = 2


class StopFlag:
    """Set by signals, a vanished parent or a closed stdout; read between updates."""

    def __init__(self, parent_pid: int) -> None:
        self.parent_pid = parent_pid
        self.reason = ""

    def set(self, reason: str) -> None:
        self.reason = self.reason or reason

    def __call__(self) -> bool:
        if not self.reason and self.parent_pid > 1 and os.getppid() != self.parent_pid:
            self.reason = "the parent process exited"
        return bool(self.reason)


class EventWriter:
    """One JSON line per event on `stream`; a closed pipe stops the run instead of failing."""

    def __init__(self, stream: TextIO, stop: StopFlag) -> None:
        self.stream = stream
        self.stop = stop
        self.closed = False

    def __call__(self, event: events.Event) -> None:
        if self.closed:
            return
        try:
            self.stream.write(events.encode(event) + "\n")
            self.stream.flush()
        except (BrokenPipeError, ValueError, OSError):
            self.closed = True
            self.stop.set("nobody is reading the training output")


# Why a training stopped, in the racer's words: the signals mean what the racer did.
STOP_REASONS = {
    signal.SIGTERM: "on request",
    signal.SIGINT: "with Ctrl+C",
    signal.SIGHUP: "because its terminal closed",
}


def _install_signal_handlers(stop: StopFlag) -> None:
    def handler(signum: int, frame: FrameType | None) -> None:
        del frame
        stop.set(STOP_REASONS.get(signal.Signals(signum), signal.Signals(signum).name))

    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, handler)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m sim.training.worker",
        description="Train one racer-tui model, streaming JSON events on stdout.",
    )
    parser.add_argument("model", help="model name in the garage, or a model folder path")
    parser.add_argument("--minutes", type=float, default=None, help="training time limit")
    parser.add_argument("--cars", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument(
        "--processes",
        type=int,
        default=None,
        help="processes stepping the cars (default: the cores less one)",
    )
    parser.add_argument("--seed", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument("--checkpoint-seconds", type=float, default=10.0, help=argparse.SUPPRESS)
    parser.add_argument("--evaluation-seconds", type=float, default=5.0, help=argparse.SUPPRESS)
    parser.add_argument("--min-samples", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument("--max-samples", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument("--parent-pid", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument(
        "--reward-seconds",
        type=float,
        default=None,
        help=f"time limit on each reward function call (default {DEFAULT_REWARD_SECONDS:g} s)",
    )
    parser.add_argument(
        "--reward-memory-mb",
        type=float,
        default=DEFAULT_MEMORY_MB,
        help=f"memory the reward function may use in each process (default {DEFAULT_MEMORY_MB})",
    )
    parser.add_argument("--die-with-parent", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument(
        "--opponent",
        action="append",
        default=[],
        help="a car on the track with every training car (repeat for more)",
    )
    return parser


def _event_stream() -> TextIO:
    """The events' own descriptor (not inherited by a program the process runs); stdout
    becomes stderr, so a print (the reward function's, a library's) never lands between
    two events, nor keeps the parent's pipe open in a process started from here."""
    sys.stdout.flush()
    stream = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return stream


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    parent = args.parent_pid if args.parent_pid is not None else os.getppid()
    if args.die_with_parent:
        # Killed with it: checkpoints are written atomically, so the last one is kept.
        die_with_parent(parent, exit_code=EXIT_FAILED)
    stop = StopFlag(parent)
    _install_signal_handlers(stop)
    emit = EventWriter(_event_stream(), stop)
    seconds = DEFAULT_REWARD_SECONDS if args.reward_seconds is None else args.reward_seconds
    if not (seconds > 0 and seconds < float("inf")):
        emit(_failed(f"--reward-seconds must be a positive number, not {seconds:g}"))
        return EXIT_USER_ERROR
    try:
        memory_mb = reward_sandbox.check_memory_mb(args.reward_memory_mb)
    except ValueError as error:
        emit(_failed(f"--reward-memory-mb: {error}"))
        return EXIT_USER_ERROR
    # The simulation processes (started by "spawn") read the memory limit from here.
    os.environ[reward_sandbox.MEMORY_ENV] = str(memory_mb)
    reward_sandbox.set_memory_budget(memory_mb)  # held to while the file loads, here too
    reward_sandbox.become_subreaper()
    # Before any update: its buffers are then reused, not faulted in again (2 threads wait
    # on each other's faults). Where the allocator cannot, it trains as before.
    keep_freed_memory()
    reward_guard.guard_reward_calls()
    warnings.filterwarnings("ignore")  # library chatter must not reach the racer
    try:
        return _train(args, emit, stop, seconds, memory_mb)
    except BaseException as error:  # the last line must say what happened
        emit(_failed(describe_failure(error), error))
        return EXIT_FAILED
    finally:
        # Whatever a reward function left running ends with the training.
        reward_sandbox.end_descendants()


def _failed(message: str, error: BaseException | None = None) -> events.Ended:
    problem, fix = failure_remedy(error) if error is not None else ("", None)
    return events.Ended(
        elapsed=0.0,
        kind="failed",
        message=message,
        total_steps=0,
        episodes=0,
        best_progress=0.0,
        best_lap=None,
        problem=problem,
        fix=fix.name if fix is not None else "",
    )


# Held for the life of the process: the kernel lets go of it however the process ends.
_HELD_LOCKS: list[object] = []


def _lock_for_training(path: Path) -> bool:
    """Take the model's training lock, or False when another process holds it. Two
    trainings started at the same moment both find no running state; only one gets the
    lock, so they never write over each other's checkpoints."""

    handle = path.open("a+b")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        return False
    _HELD_LOCKS.append(handle)
    return True


def _train(
    args: argparse.Namespace, emit: EventWriter, stop: StopFlag, seconds: float, memory_mb: int
) -> int:
    from sim.training.fleet_parts import default_processes  # noqa: PLC0415 (torch: after the run's options are checked)
    from sim.training.trainer import RunOptions, Trainer  # noqa: PLC0415 (torch: after the run's options are checked)

    try:
        folder = open_model(args.model)

        def stuck(error: RewardFunctionError) -> None:
            # From the watchdog thread: the call cannot be interrupted, so the run cannot
            # go on; its last checkpoint stays on disk.
            emit(_failed(str(error), error))

        # Every call of the racer's reward function (and loading its file) is timed: one
        # that hangs fails the training in a sentence naming its line.
        reward_sandbox.install_call_limit(seconds, folder.reward_file, stuck)
        # What the reward imports is imported first: its load and first call are timed.
        reward_sandbox.preimport(folder.reward_source())
        if folder.is_training() or not _lock_for_training(folder.training_lock_file):
            raise ModelError(
                f"model {folder.name!r} is already training in another process; "
                "stop that one first."
            )
        options = RunOptions(
            minutes=args.minutes,
            cars=args.cars,
            processes=default_processes() if args.processes is None else args.processes,
            seed=args.seed,
            checkpoint_seconds=args.checkpoint_seconds,
            evaluation_seconds=args.evaluation_seconds,
            min_samples=args.min_samples,
            max_samples=args.max_samples,
            reward_memory_mb=memory_mb,
            opponents=tuple(args.opponent),
        )
        import torch  # noqa: PLC0415 (torch: after the run's options are checked)

        torch.set_num_threads(1)
        trainer = Trainer(folder, emit, stop, options)
    except RemedyError as error:  # every user error: the racer's sentence
        emit(_failed(str(error), error))
        return EXIT_USER_ERROR
    ended = trainer.run()
    if ended.kind == "stopped" and stop.reason:
        ended = events.Ended(
            elapsed=ended.elapsed,
            kind=ended.kind,
            message=f"training was stopped {stop.reason}",
            total_steps=ended.total_steps,
            episodes=ended.episodes,
            best_progress=ended.best_progress,
            best_lap=ended.best_lap,
        )
    emit(ended)
    return EXIT_FAILED if ended.kind == "failed" else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The audit guard: what a racer's reward function may not do while it runs, refused at
its line (sim.reward.sandbox says how this fits with the rest of the containment).

Python calls an audit hook at each sensitive operation (PEP 578). In a process that runs
reward code, `guard_reward_calls` installs one that, while a reward call runs (and while
its file loads, and in any thread racer code started), refuses starting a process
(subprocess, os.fork, os.system, os.posix_spawn, os.exec*), sending a signal, calling C
through ctypes, changing the process's limits and ending the process (os._exit, os.abort,
which make no audit event and are wrapped instead): each raises `ForbiddenInReward` at
the racer's line, and a call that swallows it still fails when it returns. With
`guard_files`, opening, listing or changing a file outside what a reward may read is a
PermissionError, as Landlock gives one.

An audit hook is not a security boundary: Python code that means to can get around it
(reaching racer-tui's own modules, for one). What must hold against such code holds by
the kernel: the memory limit, Landlock, and the process session killed as a whole.
"""

from __future__ import annotations

import contextlib
import errno
import os
import site
import sys
import threading
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sim.reward import limit as reward_limit


class ForbiddenInReward(BaseException):
    """Raised inside a reward call at a thing a reward may not do. A BaseException, so a
    racer's `except Exception:` does not swallow it (a bare `except:` that does is caught
    when the call returns)."""

    def __init__(self, action: str) -> None:
        super().__init__(action)
        self.action = action  # e.g. "starts a process (subprocess.Popen)"
        # Innermost first; file names and line numbers only: reading source lines would
        # open files, inside the very hook that judges opening them.
        self.frames = [
            (frame.f_code.co_filename, line)
            for frame, line in traceback.walk_stack(sys._getframe(1))
        ]

    def line_in(self, filename: str) -> int | None:
        """The innermost line of `filename` that was running when it was refused."""
        return next((line for name, line in self.frames if name == filename), None)


def python_tree() -> list[Path]:
    """Where Python, its libraries and racer-tui are: a reward's lazy imports read there.
    Not every sys.path entry: `python -m` puts the working folder there, which may be the
    racer's home."""

    roots = {sys.prefix, sys.exec_prefix, sys.base_prefix, sys.base_exec_prefix}
    roots.update(site.getsitepackages())
    roots.add(site.getusersitepackages())
    roots.add(str(Path(__file__).resolve().parent.parent))  # racer-tui's own packages
    return sorted({Path(os.path.realpath(root)) for root in roots if os.path.isdir(root)})


SYSTEM_READS = (
    "/usr/lib",
    "/usr/lib64",
    "/usr/local/lib",
    "/lib",
    "/lib64",
    "/etc/ld.so.cache",
    "/etc/localtime",
    "/usr/share/zoneinfo",
    "/dev/urandom",
    "/dev/random",
    "/proc/self",
)


_FORBIDDEN = {
    "os.fork": "starts a process",
    "os.forkpty": "starts a process",
    "os.system": "starts a process",
    "os.posix_spawn": "starts a process",
    "os.spawn": "starts a process",
    "os.exec": "starts a process",
    "subprocess.Popen": "starts a process",
    "os.startfile": "starts a process",
    "os.kill": "sends a signal",
    "os.killpg": "sends a signal",
    "signal.pthread_kill": "sends a signal",
    "ctypes.dlopen": "calls C code through ctypes",
    "ctypes.dlsym": "calls C code through ctypes",
    "ctypes.dlsym/handle": "calls C code through ctypes",
    "ctypes.call_function": "calls C code through ctypes",
    "resource.setrlimit": "changes its process's limits",
    "resource.prlimit": "changes its process's limits",
}
_refused: ForbiddenInReward | None = None
_guarded = False
_real_exit = os._exit
# racer-tui's own threads in a guarded process (the watchdog); any other Python thread
# was started by racer code, and is refused what a reward call is.
_own_threads: set[int] = set()


def _in_reward_call() -> bool:
    limit = reward_limit._ACTIVE
    if limit is None:
        return False
    ident = threading.get_ident()
    if ident == threading.main_thread().ident:
        return bool(limit.started)
    return ident not in _own_threads


def _refuse(action: str) -> None:
    global _refused  # noqa: PLW0603 - read by the call that was running
    limit = reward_limit._ACTIVE
    assert limit is not None
    refusal = ForbiddenInReward(action)
    _refused = refusal
    limit.fired = limit.started  # the call fails when it returns, even if it swallows this
    raise refusal


# Events that change files; "open" is judged by its mode, listing a folder by its place.
_FILE_CHANGES = frozenset(
    {
        "os.remove",
        "os.rename",
        "os.mkdir",
        "os.rmdir",
        "os.truncate",
        "os.chmod",
        "os.chown",
        "os.link",
        "os.symlink",
        "os.utime",
    }
)
_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND
_readable: tuple[str, ...] | None = None  # where a reward may read; None: not guarded


def _audit(event: str, args: tuple[Any, ...]) -> None:
    what = _FORBIDDEN.get(event)
    if what is not None:
        if _in_reward_call():
            _refuse(f"{what} ({event})")
    elif (
        _readable is not None
        and (event in ("open", "os.listdir", "os.scandir") or event in _FILE_CHANGES)
        and _in_reward_call()
    ):
        _judge_file(event, args)


def _judge_file(event: str, args: tuple[Any, ...]) -> None:
    """A PermissionError, as the system gives one, for a file a reward may not touch (the
    same files Landlock closes off, for systems and moments it does not cover)."""
    path = args[0] if args else None
    if isinstance(path, int) or path is None:
        return  # an open descriptor, or the working folder: nothing new is reached
    real = os.path.realpath(os.fsdecode(path))
    if real == os.devnull:
        return
    writing = event in _FILE_CHANGES
    if event == "open":
        mode, flags = (args[1], args[2]) if len(args) >= 3 else (None, 0)
        writing = bool(isinstance(mode, str) and set(mode) & set("wax+")) or bool(
            isinstance(flags, int) and flags & _WRITE_FLAGS
        )
    assert _readable is not None
    if writing or not any(real == root or real.startswith(root + os.sep) for root in _readable):
        raise PermissionError(errno.EACCES, "a reward function may not reach this file", path)


def _exit_guard(name: str, real: Callable[..., Any]) -> Callable[..., Any]:
    def guarded(*args: Any) -> Any:
        if _in_reward_call():
            _refuse(f"ends its process ({name})")
        return real(*args)

    return guarded


def guard_files(reward_file: str | Path | None) -> None:
    """From now on, a reward call may read only where Landlock would let it
    (sim.reward.sandbox.close_off_files), and write nowhere: the file guard that holds
    where Landlock does not."""
    global _readable  # noqa: PLW0603
    reads = [*python_tree(), *(Path(path) for path in SYSTEM_READS)]
    if reward_file is not None and Path(reward_file).is_file():
        reads.append(Path(os.path.realpath(reward_file)).parent)
    _readable = tuple(os.path.realpath(path) for path in reads)


def files_judged() -> bool:
    """Whether `guard_files` keeps reward calls in this process from files."""
    return _readable is not None


def guard_reward_calls() -> None:
    """Refuse, during reward calls, what a reward may not do (see the module docstring).
    Once per process: an audit hook cannot be removed."""
    global _guarded  # noqa: PLW0603
    if _guarded:
        return
    _own_threads.update(thread.ident for thread in threading.enumerate() if thread.ident)
    sys.addaudithook(_audit)
    guarded_exit = _exit_guard("os._exit", _real_exit)
    os._exit = guarded_exit
    with contextlib.suppress(ImportError):
        import posix  # noqa: PLC0415 (not every platform has posix)

        posix._exit = guarded_exit
    os.abort = _exit_guard("os.abort", os.abort)
    _guarded = True


def take_refusal(started: float) -> ForbiddenInReward | None:
    """The refusal of the call that began at `started`, if any (and forget it)."""
    global _refused
    refused, _refused = _refused, None
    limit = reward_limit._ACTIVE
    if refused is None or limit is None or limit.fired != started:
        return None
    return refused


def exit_now(code: int) -> None:
    """End this process at once (racer-tui's own `os._exit`, never refused)."""
    _real_exit(code)


def own_thread(name: str) -> None:
    """Count racer-tui's thread `name` (started before any racer code ran) as its own."""
    _own_threads.update(
        thread.ident for thread in threading.enumerate() if thread.name == name and thread.ident
    )


def is_own_thread(ident: int) -> bool:
    """Whether the thread `ident` counts as racer-tui's own (never refused as racer code)."""
    return ident in _own_threads

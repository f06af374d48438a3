"""What a process that runs a racer's reward function does to contain it, beyond the time
limit on each call (sim.reward_limit).

A reward function is the racer's own Python. DeepRacer runs it inside AWS's simulation
container; here it runs on the racer's (or a league host's) machine, so every process that
runs it (the check's child, sim.reward_probe; the training's processes, sim.training)
contains it:

- **memory**: the process may hold only `memory_mb` more than it did when the reward was
  loaded (RLIMIT_DATA); an allocation past that raises MemoryError inside the reward and is
  reported as "used more than N MB of memory" with its line;
- **no process, signal or C call**: while a reward call runs (and while its file loads),
  and in any thread racer code started, an audit hook refuses starting a process
  (subprocess, os.fork, os.system, os.posix_spawn, os.exec*), sending a signal, calling C
  through ctypes and ending the process (os._exit, os.abort); the refusal is an exception
  at the racer's line, reported in one sentence. What escapes the hook (a multiprocessing
  "spawn" start makes no audit event; Landlock, where there is one, refuses it the
  program) is caught by the leftovers: the check fails on a call after which the process
  has a child, and every process that runs reward code is a child subreaper that kills all
  its descendants when it ends, inside a process session its parent kills as a whole;
- **files** (sim.landlock, where Linux has Landlock): the process may read only Python's
  own files, racer-tui's, the system's libraries, the reward file's folder, /proc/self and
  /dev/null, /dev/urandom, and write nowhere (the trainer's own process: only its model's
  folder); no TCP. `landlock_status()` says whether it was applied and, if not, why.
"""

from __future__ import annotations

import contextlib
import errno
import os
import resource
import signal
import sys
import threading
import traceback
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from sim import landlock, reward_limit

if TYPE_CHECKING:
    from sim.reward_function import RewardFunctionError

DEFAULT_MEMORY_MB = 2048  # DeepRacer's reward code never needs more than a few MB
MIN_MEMORY_MB = 16
MAX_MEMORY_MB = 1 << 20
# How the training's simulation processes (started by multiprocessing "spawn", which hands
# them nothing but their setup) learn the limit the racer asked for.
MEMORY_ENV = "RACER_TUI_REWARD_MEMORY_MB"
# What DeepRacer lets a reward function import: imported before the files are closed off,
# so a reward's `import` finds them loaded (the Python tree stays readable for the rest).
DEEPRACER_MODULES = ("math", "random", "numpy", "scipy", "scipy.spatial", "shapely.geometry")


class ForbiddenInReward(BaseException):
    """Raised inside a reward call at a thing a reward may not do. A BaseException, so a
    racer's `except Exception:` does not swallow it (a bare `except:` that does is caught
    when the call returns)."""

    def __init__(self, action: str) -> None:
        super().__init__(action)
        self.action = action  # e.g. "starts a process (subprocess.Popen)"
        self.frames = [
            (frame.filename, frame.lineno) for frame in traceback.extract_stack(sys._getframe(1))
        ]

    def line_in(self, filename: str) -> int | None:
        """The innermost line of `filename` that was running when it was refused."""
        lines = [line for name, line in self.frames if name == filename and line is not None]
        return lines[-1] if lines else None


# --- memory ------------------------------------------------------------------------------
_memory_mb: int | None = None


def memory_limit_mb() -> int | None:
    """The reward's memory in this process (`limit_memory`, `set_memory_budget`), if any."""
    return _memory_mb


def set_memory_budget(megabytes: int) -> None:
    """The memory a reward may use in this process, held to while its file loads (see
    `loading_limit`) before `limit_memory` holds the whole process to it."""
    global _memory_mb  # noqa: PLW0603
    _memory_mb = megabytes


@contextlib.contextmanager
def loading_limit() -> Iterator[None]:
    """While a reward file's module-level code runs: the process may grow by the reward's
    memory and no more (the soft RLIMIT_DATA, put back after; the code may not change it,
    see `_FORBIDDEN`). Nothing when no budget is set."""
    if _memory_mb is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    limit = data_bytes() + _memory_mb * 1024 * 1024
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))


def check_memory_mb(value: float) -> int:
    """A memory setting as whole MB; ValueError (one sentence) when out of range."""
    if not (MIN_MEMORY_MB <= value <= MAX_MEMORY_MB) or value != int(value):
        raise ValueError(
            f"the reward memory limit must be a whole number of MB from {MIN_MEMORY_MB} to "
            f"{MAX_MEMORY_MB}, not {value:g}"
        )
    return int(value)


def data_bytes() -> int:
    """What this process holds that RLIMIT_DATA counts (VmData), or 0 when unknown."""
    with contextlib.suppress(OSError, ValueError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmData:"):
                return int(line.split()[1]) * 1024
    return 0


def limit_memory(megabytes: int, *, learner_mb: int = 0) -> None:
    """Let this process grow by at most `megabytes` (and `learner_mb` for racer-tui's own
    work in it) from now on (RLIMIT_DATA, soft and hard: the racer's code cannot raise it
    again)."""
    global _memory_mb  # noqa: PLW0603 - one limit per process, read by error messages
    limit = data_bytes() + (megabytes + learner_mb) * 1024 * 1024
    _soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))
    _memory_mb = megabytes


def memory_from_environment() -> int:
    """The limit a training's process was asked for (see MEMORY_ENV)."""
    try:
        return check_memory_mb(float(os.environ.get(MEMORY_ENV, DEFAULT_MEMORY_MB)))
    except ValueError:
        return DEFAULT_MEMORY_MB


# --- the audit guard ---------------------------------------------------------------------
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
    """From now on, a reward call may read only where `close_off_files` lets it, and write
    nowhere (by the audit hook: the file guard that holds where Landlock does not)."""
    global _readable  # noqa: PLW0603
    reads = [*python_tree(), *(Path(path) for path in SYSTEM_READS)]
    if reward_file is not None and Path(reward_file).is_file():
        reads.append(Path(os.path.realpath(reward_file)).parent)
    _readable = tuple(os.path.realpath(path) for path in reads)


def files_guarded() -> bool:
    """Whether a reward in this process is kept from files (Landlock or the file guard)."""
    return _readable is not None or _landlock_status == "applied"


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
        import posix

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


# --- processes ---------------------------------------------------------------------------
_PR_SET_CHILD_SUBREAPER = 36


def become_subreaper() -> bool:
    """Make orphans among this process's descendants its children (Linux), so none can
    slip out from under `end_descendants` by losing its parent."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    return bool(ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)


def has_child_process() -> bool:
    """Whether this process has a child, living or not yet reaped (one system call)."""
    if not hasattr(os, "waitid"):  # macOS: ask psutil
        return bool(_child_pids())
    try:
        os.waitid(os.P_ALL, 0, os.WEXITED | os.WNOHANG | os.WNOWAIT)
    except ChildProcessError:
        return False
    return True


def wait_for_exit(pid: int) -> None:
    """Wait until child `pid` has exited, without reaping it (its exit status stays for
    whoever waits for it, and its id stays its own until then)."""
    if hasattr(os, "waitid"):
        with contextlib.suppress(ChildProcessError, OSError):
            os.waitid(os.P_PID, pid, os.WEXITED | os.WNOWAIT)
        return
    import time

    import psutil

    while True:  # no waitid (macOS): look twice a second
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                return
        except psutil.Error:
            return
        time.sleep(0.5)


def _child_pids() -> set[int]:
    """This process's children, from /proc/self (readable inside Landlock, unlike /proc)."""
    pids: set[int] = set()
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        tasks = []
    for task in tasks:
        with contextlib.suppress(OSError, ValueError):
            pids.update(
                int(pid) for pid in Path(f"/proc/self/task/{task}/children").read_text().split()
            )
    if not tasks:  # no /proc: ask psutil
        import psutil

        with contextlib.suppress(psutil.Error):
            pids.update(child.pid for child in psutil.Process().children())
    return pids


# Rounds of killing children before giving up: each round's orphans become this process's
# children (it is their subreaper) for the next.
_KILL_ROUNDS = 64


def end_descendants() -> int:
    """SIGKILL every descendant of this process (a subreaper: see `become_subreaper`) and
    reap them; how many were ended."""
    ended = 0
    for _round in range(_KILL_ROUNDS):
        children = _child_pids()
        if not children:
            break
        for pid in children:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)
        for pid in children:
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)
        ended += len(children)
    return ended


def kill_session(leader_pid: int) -> None:
    """SIGKILL the process group of a child started with `start_new_session` (its pid is
    the group's), whatever is left of it."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(leader_pid, signal.SIGKILL)


# --- files -------------------------------------------------------------------------------
_landlock_status = "not applied"


def landlock_status() -> str:
    """ "applied", or why this process's files are not closed off."""
    return _landlock_status


def python_tree() -> list[Path]:
    """Where Python, its libraries and racer-tui are: a reward's lazy imports read there.
    Not every sys.path entry: `python -m` puts the working folder there, which may be the
    racer's home."""
    import site

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


def preimport() -> None:
    """Import what DeepRacer lets a reward import (skipping any not installed)."""
    import importlib

    for name in DEEPRACER_MODULES:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)


def close_off_files(
    reward_file: str | Path | None,
    writable: Iterable[Path] = (),
    *,
    reads: Iterable[Path] = (),
    scope_signals: bool = True,
) -> str:
    """Landlock this process: read only the Python tree, the system's libraries, the reward
    file's folder, /proc/self and `reads`; write only to /dev/null and `writable`. Call
    after every import the process needs. Returns (and records) "applied" or why not."""
    global _landlock_status  # noqa: PLW0603
    preimport()
    reads = [*python_tree(), *(Path(path) for path in SYSTEM_READS), *reads]
    if reward_file is not None and Path(reward_file).is_file():
        reads.append(Path(os.path.realpath(reward_file)).parent)
    problem = landlock.restrict(reads, [Path("/dev/null"), *writable], scope_signals=scope_signals)
    _landlock_status = "applied" if problem is None else problem
    return _landlock_status


# --- the call limit, said the same way everywhere ---------------------------------------
def stuck_problem(seconds: float) -> str:
    return (
        f"reward_function did not return within {seconds:g} s and could not be interrupted "
        "(it blocks or catches the interruption, or is stuck inside a library call)"
    )


def memory_problem(megabytes: int) -> str:
    return f"reward_function used more than {megabytes} MB of memory"


def install_call_limit(
    seconds: float, reward_file: str | Path, report: Callable[[RewardFunctionError], None]
) -> reward_limit.CallLimit:
    """Time every reward call in this process; a call that cannot be interrupted is reported
    through `report` (from the watchdog thread) and ends the process."""
    limit = reward_limit.install(seconds)
    guard_files(reward_file)
    _own_threads.update(  # the watchdog, started by the line above before any racer code
        thread.ident
        for thread in threading.enumerate()
        if thread.name == reward_limit.WATCHDOG_NAME and thread.ident
    )
    names = {str(reward_file), os.path.abspath(reward_file)}  # as it may have been compiled

    def stuck(limit_seconds: float) -> None:
        from sim.reward_function import RewardFunctionError

        main = sys._current_frames().get(threading.main_thread().ident or 0)
        report(
            RewardFunctionError(
                reward_file,
                stuck_problem(limit_seconds),
                _frame_line(main, names),
                advice="make it return faster",
            )
        )
        exit_now(1)

    limit.on_stuck = stuck
    return limit


def _frame_line(frame: FrameType | None, filenames: set[str]) -> int | None:
    """The innermost line of the racer's file on the stack from `frame` outwards."""
    while frame is not None:
        if frame.f_code.co_filename in filenames:
            return frame.f_lineno
        frame = frame.f_back
    return None

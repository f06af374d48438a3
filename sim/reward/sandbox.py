"""What a process that runs a racer's reward function does to contain it, beyond the time
limit on each call (sim.reward.limit).

A reward function is the racer's own Python. DeepRacer runs it inside AWS's simulation
container; here it runs on the racer's (or a league host's) machine, so every process that
runs it (the check's child, sim.reward.probe; the training's processes, sim.training)
contains it:

- **memory**: while the file loads, and from the first call on, the process may grow by
  only `memory_mb` (RLIMIT_DATA; the trainer's own process keeps room for its learner
  besides); an allocation past that raises MemoryError inside the reward, reported as
  "used more than N MB of memory" with its line;
- **processes**: the audit guard (sim.reward.guard) refuses a process, a signal, a C call
  or an exit at the racer's line. What gets past it (a multiprocessing "spawn" start
  makes no audit event; where there is Landlock, the kernel refuses it the program) is
  caught by the leftovers: the check fails a call after which the process has a child;
  every process that runs reward code is the subreaper of everything under it and kills
  it all when it ends (`end_descendants`); and its parent kills its whole process session
  (`kill_session`) once it has exited;
- **files**: where Linux has Landlock (sim.reward.landlock), once its own reading is done the
  process may read only Python's files, racer-tui's, the system's libraries, the reward
  file's folder, /proc/self, /dev/urandom and /dev/null, and write nowhere but /dev/null
  (the trainer's own process: its model's folder too); no TCP, no program run.
  `landlock_status()` says whether it was applied and, if not, why. The audit guard
  holds reward calls to the same files where Landlock does not (`files_guarded`).
"""

from __future__ import annotations

import ast
import contextlib
import ctypes
import importlib
import os
import resource
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

import psutil

from sim.reward import landlock
from sim.reward import limit as reward_limit
from sim.reward.errors import RewardFunctionError
from sim.reward.guard import (
    SYSTEM_READS,
    exit_now,
    files_judged,
    guard_files,
    own_thread,
    python_tree,
)

if TYPE_CHECKING:
    from sim.reward.errors import RewardFunctionError

DEFAULT_MEMORY_MB = 2048  # DeepRacer's reward code never needs more than a few MB
MIN_MEMORY_MB = 16
MAX_MEMORY_MB = 1 << 20
# How the training's simulation processes (started by multiprocessing "spawn", which hands
# them nothing but their setup) learn the limit the racer asked for.
MEMORY_ENV = "RACER_TUI_REWARD_MEMORY_MB"
# What DeepRacer lets a reward function import. Those a reward's code names are imported
# before its file loads, so the import costs none of its time and memory limits (scipy's
# modules take a second); the Python tree stays readable for any other.
DEEPRACER_PACKAGES = frozenset({"math", "random", "numpy", "scipy", "shapely"})


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
    see sim.reward.guard). Nothing when no budget is set."""
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    limit = None if _memory_mb is None else _data_limit(_memory_mb, hard)
    if limit is None or not _set_data_limit(limit, hard):
        yield
        return
    try:
        yield
    finally:
        _set_data_limit(soft, hard)


def _data_limit(megabytes: int, hard: int) -> int | None:
    """What the process holds now plus `megabytes`, within `hard`; None when what it holds
    cannot be read (no /proc): a limit then could be below it."""
    held = data_bytes()
    if not held:
        return None
    limit = held + megabytes * 1024 * 1024
    return limit if hard == resource.RLIM_INFINITY else min(limit, hard)


def _set_data_limit(soft: int, hard: int) -> bool:
    try:
        resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))
    except (OSError, ValueError):  # a system that will not have it: no limit, not a crash
        return False
    return True


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


def limit_memory(megabytes: int, *, learner_mb: int = 0) -> bool:
    """Let this process grow by at most `megabytes` (and `learner_mb` for racer-tui's own
    work in it) from now on (RLIMIT_DATA, soft and hard: the racer's code cannot raise it
    again). False when this system cannot say or set it."""
    global _memory_mb  # noqa: PLW0603 - one limit per process, read by error messages
    _memory_mb = megabytes
    _soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    limit = _data_limit(megabytes + learner_mb, hard)
    return limit is not None and _set_data_limit(limit, limit)


def memory_from_environment() -> int:
    """The limit a training's process was asked for (see MEMORY_ENV)."""
    try:
        return check_memory_mb(float(os.environ.get(MEMORY_ENV, DEFAULT_MEMORY_MB)))
    except ValueError:
        return DEFAULT_MEMORY_MB


# --- processes ---------------------------------------------------------------------------
_PR_SET_CHILD_SUBREAPER = 36


def become_subreaper() -> bool:
    """Make orphans among this process's descendants its children (Linux), so none can
    slip out from under `end_descendants` by losing its parent."""
    if not sys.platform.startswith("linux"):
        return False

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


def files_guarded() -> bool:
    """Whether a reward in this process is kept from files (Landlock or the file guard)."""
    return files_judged() or _landlock_status == "applied"


def landlock_status() -> str:
    """ "applied", or why this process's files are not closed off."""
    return _landlock_status


def named_imports(source: str) -> list[str]:
    """The modules of DEEPRACER_PACKAGES that `source` imports, anywhere in it (`from
    scipy import spatial` names scipy.spatial too: it may be a module)."""
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError):
        return []
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return sorted(name for name in names if name.split(".")[0] in DEEPRACER_PACKAGES)


def preimport(source: str) -> None:
    """Import the modules DeepRacer allows that `source` names (what is not a module, or
    not installed, is left to the reward's own import to say)."""

    for name in named_imports(source):
        with contextlib.suppress(Exception):
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
    after every file the process itself needs is read. Returns (and records) "applied" or
    why not."""
    global _landlock_status  # noqa: PLW0603
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


def memory_problem(megabytes: int, who: str = "reward_function") -> str:
    return f"{who} used more than {megabytes} MB of memory"


def install_call_limit(
    seconds: float, reward_file: str | Path, report: Callable[[RewardFunctionError], None]
) -> reward_limit.CallLimit:
    """Time every reward call in this process; a call that cannot be interrupted is reported
    through `report` (from the watchdog thread) and ends the process."""
    limit = reward_limit.install(seconds)
    guard_files(reward_file)
    own_thread(reward_limit.WATCHDOG_NAME)  # started by the line above, before racer code
    names = {str(reward_file), os.path.abspath(reward_file)}  # as it may have been compiled

    def stuck(limit_seconds: float) -> None:

        main = sys._current_frames().get(threading.main_thread().ident or 0)
        report(
            RewardFunctionError(
                reward_file,
                stuck_problem(limit_seconds),
                _frame_line(main, names),
                advice="make it return faster",
            )
        )
        end_descendants()  # what the racer's code may have left goes with the process
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

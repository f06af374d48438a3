"""A reward function is contained at run time (sim.reward.sandbox): it cannot leave a
process behind, allocate without bound, end its process unnamed or (where Linux has
Landlock) read a racer's secrets or write outside; each is said in one sentence naming
the file and line, and no process of the check outlives it."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import psutil
import pytest

from sim.reward import landlock
from sim.reward import sandbox as reward_sandbox
from sim.reward.errors import RewardFunctionError
from sim.reward.probe import check_reward_source
from tests.leftover_processes import processes_with

pytestmark = pytest.mark.usefixtures("no_leftover_processes")

LIMIT = 1.0


def failure(source: str, name: str = "reward.py", memory_mb: int = 2048) -> str:
    with pytest.raises(RewardFunctionError) as caught:
        check_reward_source(textwrap.dedent(source), name, seconds=LIMIT, memory_mb=memory_mb)
    return str(caught.value)


def sleep_seconds() -> str:
    """A `sleep` argument no other process has: how the test finds what was left."""
    return f"1000.{uuid.uuid4().int % 10**9}"


def test_a_function_that_starts_a_process_fails_and_leaves_none() -> None:
    marker = sleep_seconds()
    source = f"""\
        import subprocess
        def reward_function(params):
            subprocess.Popen(["sleep", "{marker}"])
            return 1.0
        """
    message = failure(source)
    assert message.startswith("reward.py line 3: reward_function starts a process")
    assert processes_with(marker) == []


def test_forking_and_c_calls_are_refused_at_their_line() -> None:
    fork = "import os\ndef reward_function(params):\n    os.fork()\n    return 1.0\n"
    assert failure(fork).startswith("reward.py line 3: reward_function starts a process (os.fork)")
    through_c = (
        "import ctypes\n"
        "def reward_function(params):\n"
        "    ctypes.CDLL(None).fork()\n"
        "    return 1.0\n"
    )
    assert "line 3: reward_function calls C code through ctypes" in failure(through_c)


def test_a_refusal_the_function_swallows_still_fails_it() -> None:
    marker = sleep_seconds()
    source = f"""\
        import subprocess
        def reward_function(params):
            try:
                subprocess.Popen(["sleep", "{marker}"])
            except BaseException:
                pass
            return 1.0
        """
    assert failure(source).startswith("reward.py line 4: reward_function starts a process")
    assert processes_with(marker) == []


def test_a_process_started_where_no_audit_event_sees_it_fails_the_check() -> None:
    # multiprocessing's "spawn" makes no audit event: the look after the call finds it.
    source = """\
        import multiprocessing, time
        def reward_function(params):
            multiprocessing.get_context("spawn").Process(target=time.sleep, args=(1000,)).start()
            return 1.0
        """
    message = failure(source)
    assert "reward_function starts a process" in message, message


def test_an_allocation_over_the_limit_is_said_as_memory_with_its_line() -> None:
    source = "def reward_function(params):\n    data = bytearray(8 * 10**9)\n    return 1.0\n"
    message = failure(source, memory_mb=64)
    assert message.startswith("reward.py line 2: reward_function used more than 64 MB of memory")
    assert "catch every exception" not in message
    # Many small allocations fill the limit too, and loading the file is held to it.
    growing = "kept = [bytearray(2**20) for _ in range(200)]\ndef reward_function(params):\n"
    message = failure(growing + "    return 1.0\n", memory_mb=64)
    assert message.startswith("reward.py line 1: loading the file used more than 64 MB of memory")


def test_a_thread_the_function_starts_is_refused_a_process_too() -> None:
    marker = sleep_seconds()
    source = f"""\
        import subprocess, threading
        def start():
            subprocess.Popen(["sleep", "{marker}"])
        def reward_function(params):
            thread = threading.Thread(target=start)
            thread.start()
            thread.join()
            return 1.0
        """
    assert failure(source).startswith("reward.py line 3: reward_function starts a process")
    assert processes_with(marker) == []


needs_landlock = pytest.mark.skipif(
    landlock.abi_version() < 1,
    reason="this kernel has no Landlock: a reward's files are not closed off here",
)


@needs_landlock
def test_a_function_cannot_read_a_secret_or_write_outside(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    home = tmp_path / "home"
    (home / ".ssh").mkdir(parents=True)
    (home / ".ssh" / "id_ed25519").write_text("secret")
    monkeypatch.setenv("HOME", str(home))
    racer = tmp_path / "racer"
    racer.mkdir()
    (racer / "weights.txt").write_text("2.5")
    reward = racer / "reward.py"
    reward.write_text("def reward_function(params):\n    return 1.0\n")  # its folder is read
    reads = """\
        import os
        def reward_function(params):
            return float(len(open(os.path.expanduser("~/.ssh/id_ed25519")).read()))
        """
    message = failure(reads, str(reward))
    assert message.startswith(f"{reward} line 3: reward_function raised PermissionError")
    assert "may read only Python's files and its own folder" in message
    outside = tmp_path / "written.txt"
    writes = f"""\
        def reward_function(params):
            open({str(outside)!r}, "w").write("x")
            return 1.0
        """
    assert "line 2: reward_function raised PermissionError" in failure(writes, str(reward))
    assert not outside.exists()
    beside = f"""\
        def reward_function(params):
            return float(open({str(racer / "weights.txt")!r}).read())
        """
    assert check_reward_source(textwrap.dedent(beside), str(reward)).sample_reward == 2.5


def test_what_a_reward_may_import_still_imports() -> None:
    source = """\
        import math, random
        import numpy as np
        def reward_function(params):
            from scipy import spatial
            from shapely.geometry import Point
            import scipy.interpolate
            return float(np.clip(math.cos(0) * random.random() + Point(0, 0).x, 0, 1))
        """
    report = check_reward_source(textwrap.dedent(source), "reward.py")
    assert 0.0 <= report.sample_reward <= 1.0


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux process sessions")
def test_the_check_leaves_no_process_of_its_own() -> None:
    before = {child.pid for child in psutil.Process().children(recursive=True)}
    check_reward_source("def reward_function(params):\n    return 1.0\n", "reward.py")
    after = {child.pid for child in psutil.Process().children(recursive=True)}
    assert after <= before


GUARDED_CALL = """\
import subprocess
import sys
from sim.reward import guard as reward_guard
from sim.reward import sandbox as reward_sandbox
from sim.reward.function import load_reward_function
from sim.reward.errors import RewardFunctionError
reward_sandbox.install_call_limit(5.0, sys.argv[1], lambda error: None)
reward_guard.guard_reward_calls()
try:
    print(load_reward_function(sys.argv[1])({}))
except RewardFunctionError as error:
    print(error)
"""


def guarded_call(reward: Path, source: str) -> str:
    """What calling `source` says in a process with the audit guard and no Landlock (as
    on a system without it, or while a training loads the file)."""
    reward.write_text(textwrap.dedent(source))
    done = subprocess.run(
        [sys.executable, "-c", GUARDED_CALL, str(reward)],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    return done.stdout.strip()


def test_the_file_guard_holds_where_landlock_does_not(tmp_path: Path) -> None:
    secret = tmp_path / "home" / ".ssh" / "id_ed25519"
    secret.parent.mkdir(parents=True)
    secret.write_text("secret")
    racer = tmp_path / "racer"
    racer.mkdir()
    (racer / "weights.txt").write_text("2.5")
    reward = racer / "reward.py"
    reads = f"def reward_function(params):\n    return float(len(open({str(secret)!r}).read()))\n"
    said = guarded_call(reward, reads)
    assert said.startswith(f"{reward} line 2: reward_function raised PermissionError"), said
    outside = tmp_path / "written.txt"
    for writes in (
        f"def reward_function(params):\n    open({str(outside)!r}, 'w')\n",
        f"import os\ndef reward_function(params):\n    os.mkdir({str(outside)!r})\n",
    ):
        assert "raised PermissionError" in guarded_call(reward, writes)
    assert not outside.exists()
    listing = (
        "import os\n"
        "def reward_function(params):\n"
        f"    return len(os.listdir({str(secret.parent)!r}))\n"
    )
    assert "raised PermissionError" in guarded_call(reward, listing)
    beside = (
        "import numpy, scipy.interpolate\n"
        "def reward_function(params):\n"
        f"    return float(open({str(racer / 'weights.txt')!r}).read())\n"
    )
    assert guarded_call(reward, beside) == "2.5"


# Code that means to can get past the audit guard (it is Python reaching racer-tui's own
# modules); what it starts is still found and ended, by the kernel's means.
PAST_THE_GUARD = """\
import os
import sim.reward.limit
forked = []
def reward_function(params):
    sim.reward.limit._ACTIVE = None  # the guard now sees no call running
    if not forked:
        forked.append(1)
        if os.fork() == 0:
            os.setsid()  # out of the check's session, too
            try:  # where it may write (a training's model folder), it says it ran
                open(os.path.join(os.path.dirname(__file__), "spinning"), "w").close()
            except OSError:
                pass
            while True:
                pass
    return 1.0
"""


def processes_marked(marker: str) -> list[psutil.Process]:
    """Living processes whose environment holds `marker` (the test's children inherit it)."""
    found = []
    for process in psutil.process_iter(["status"]):
        try:
            if process.info["status"] == psutil.STATUS_ZOMBIE:
                continue
            if process.environ().get("REWARD_CONTAINMENT_MARKER") == marker:
                found.append(process)
        except psutil.Error:
            continue
    return found


def test_a_fork_that_gets_past_the_guard_fails_the_check_and_is_ended(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    marker = str(uuid.uuid4())
    monkeypatch.setenv("REWARD_CONTAINMENT_MARKER", marker)
    message = failure(PAST_THE_GUARD)
    assert message.startswith("reward.py line 4: reward_function starts a process that outlives")
    assert processes_marked(marker) == []


def test_the_modules_a_reward_names_are_imported_before_it_is_timed() -> None:
    source = (
        "import math, os\n"
        "from scipy import spatial\n"
        "def reward_function(params):\n"
        "    from shapely.geometry import Point\n"
        "    import numpy as np\n"
        "    return 1.0\n"
    )
    assert reward_sandbox.named_imports(source) == [
        "math",
        "numpy",
        "scipy",
        "scipy.spatial",
        "shapely.geometry",
        "shapely.geometry.Point",
    ]
    assert reward_sandbox.named_imports("def broken(:\n") == []
    # scipy.spatial takes about a second to import: loaded beforehand, it is not the
    # file's, and a short limit on loading holds.
    report = check_reward_source(source, "reward.py", seconds=0.25)
    assert report.sample_reward == 1.0

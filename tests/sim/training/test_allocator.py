"""A training's process keeps the memory its updates free (sim.training.allocator)."""

from __future__ import annotations

import json
import platform
import subprocess
import sys

import pytest

from sim.training.allocator import keep_freed_memory

GLIBC = platform.system() == "Linux" and platform.libc_ver()[0] == "glibc"

# Frees a 64 MB buffer and prints how much of it the process still holds (resident).
_HELD_AFTER_FREE = """
import sys
from pathlib import Path
import numpy as np
from sim.training.allocator import keep_freed_memory
if sys.argv[1] == "keep":
    assert keep_freed_memory()
def resident():
    lines = Path("/proc/self/status").read_text().splitlines()
    return int(next(l for l in lines if l.startswith("VmRSS:")).split()[1]) * 1024
before = resident()
buffer = np.ones(64 * 1024 * 1024 // 8)
del buffer
print(resident() - before)
"""


def _held_after_free(mode: str) -> int:
    done = subprocess.run(
        [sys.executable, "-c", _HELD_AFTER_FREE, mode],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    return int(done.stdout)


@pytest.mark.skipif(not GLIBC, reason="the allocator's settings are glibc's")
def test_freed_buffers_stay_with_the_process_for_the_next_update() -> None:
    megabyte = 1024 * 1024
    assert _held_after_free("as-is") < 16 * megabyte  # glibc gives a 64 MB mmap back
    assert _held_after_free("keep") > 48 * megabyte


@pytest.mark.skipif(GLIBC, reason="on glibc the allocator takes the settings")
def test_elsewhere_the_allocator_is_left_as_it_was() -> None:
    assert keep_freed_memory() is False


# The training worker, run on a model that is not there, records whether it set the
# allocator up first (the settings are a process's own: a process of its own runs it).
_WORKER_THEN_CALLS = """
import json, sys
import sim.training.worker as worker
calls = []
worker.keep_freed_memory = lambda: calls.append("kept") or True
code = worker.main(["no-such-model", "--minutes", "1"])
print(json.dumps({"code": code, "calls": calls}), file=sys.stderr)
"""


def test_the_training_process_keeps_freed_memory_before_it_trains() -> None:
    done = subprocess.run(
        [sys.executable, "-c", _WORKER_THEN_CALLS],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    ran = json.loads(done.stderr.strip().splitlines()[-1])
    assert ran["calls"] == ["kept"]
    assert ran["code"] != 0  # and the missing model failed the run in its sentence
    assert "no-such-model" in done.stdout

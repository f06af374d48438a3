"""A child process that ends with the process that started it."""

from __future__ import annotations

import ctypes
import os
import signal
import sys

_PR_SET_PDEATHSIG = 1  # Linux's prctl option: a signal for this process when its parent dies


def die_with_parent(
    parent_pid: int, signal_number: int = signal.SIGKILL, exit_code: int = 1
) -> None:
    """Be sent `signal_number` when the parent dies (Linux), so a killed app or command
    leaves no orphan behind; exit at once (`exit_code`) if it died already."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal_number))
    if os.getppid() != parent_pid:  # it died before the line above took effect
        os._exit(exit_code)

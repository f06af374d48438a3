"""The C allocator in a training's process: memory freed by one update is kept for the next.

An update allocates and frees the same large buffers hundreds of times a minute (a slice's
activations and gradients, a minibatch's frames: 5-10 MB each for a camera network). glibc's
malloc serves such sizes with fresh mmaps, and gives the heap's free top back to the kernel,
so every allocation faults its pages in again. With the update on two threads (a training on
2 processes), both threads fault at once and wait on the process's one memory map.

Kept instead: allocations below `HEAP_BELOW` come from the heap, and the heap is given back
only past `GIVE_BACK_PAST` of free memory. The process holds more for it: a one-minute
2-process camera training's trainer ended at 759 MB resident against 620 MB, within the
learner's memory margin (`sim.training.trainer.LEARNER_BASE_MB` beyond its rollout).

Measured on a 2-core AMD EPYC, one-minute trainings of a fresh camera model on 2 processes,
three each, alternating with the code before: the update took 153-173 µs a sample (the
median of each run's updates) instead of 179-187, and the minute took 56,832-64,320 steps
instead of 55,616-58,112. On one process (one thread) no clear change showed. Setting only the
give-back threshold made the update far slower (296-309 µs): that turns off glibc's own
rising mmap threshold.
"""

from __future__ import annotations

import ctypes
import platform
from typing import Final

# mallopt's parameters (glibc's malloc.h).
_M_TRIM_THRESHOLD: Final = -1
_M_MMAP_THRESHOLD: Final = -3

HEAP_BELOW: Final = 256 * 1024 * 1024
GIVE_BACK_PAST: Final = 1024 * 1024 * 1024


def keep_freed_memory() -> bool:
    """Have this process's allocator keep freed memory (see above); False where the C
    library is not glibc or refuses, and the allocator is left as it was."""
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    # The mmap threshold first: setting either turns off glibc's own adjustment of both.
    return bool(mallopt(_M_MMAP_THRESHOLD, HEAP_BELOW)) and bool(
        mallopt(_M_TRIM_THRESHOLD, GIVE_BACK_PAST)
    )

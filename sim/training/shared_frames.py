"""A simulation process's pooled camera frames handed to the trainer in shared memory.

A part that acts for its cars (sim.training.actor) answers every step with its cars'
pooled frames, 19 kB a car: through the pipe that is about 600 kB a step for 32 cars,
pickled by the part, copied through the kernel and unpickled by the trainer, and with
several parts the trainer reads them one after another. Each part instead writes them
into memory it shares with the trainer, and the trainer copies them out of it.

The exchange is lockstep, so nothing else guards the memory: a part writes its frames only
while it answers a message, and the trainer copies them out (`take`) before it sends that
part its next one. The memory is an unlinked file (multiprocessing's `RawArray`): it goes
with the last process that maps it, however that process ends.
"""

from __future__ import annotations

import ctypes
from dataclasses import replace
from typing import Any

import numpy as np

from sim.training.acting import Acting

CAMERA = "camera"


class SharedFrames:
    """Room for one part's pooled camera frames: `cars` frames of `shape` (float32)."""

    def __init__(self, memory: Any, cars: int, shape: tuple[int, ...]) -> None:
        self._memory = memory  # kept: the view below lives on it
        self._frames = np.frombuffer(memory, dtype=np.float32).reshape(cars, *shape)

    @classmethod
    def allocate(cls, context: Any, cars: int, shape: tuple[int, ...]) -> SharedFrames:
        """New shared memory from a multiprocessing `context` (pass the object to the part's
        process as it starts: shared memory crosses to a process only then)."""
        memory = context.RawArray(ctypes.c_float, cars * int(np.prod(shape)))
        return cls(memory, cars, shape)

    def __reduce__(self) -> tuple[Any, ...]:
        # The memory itself, never a copy of the frames (only at a process's start).
        return (SharedFrames, (self._memory, self._frames.shape[0], self._frames.shape[1:]))

    def put(self, acting: Acting) -> Acting:
        """In the part: the frames written here; the acting to send, without them."""
        pooled = acting.pooled
        frames = pooled[CAMERA] if isinstance(pooled, dict) else pooled
        self._frames[...] = frames
        left = {**pooled, CAMERA: None} if isinstance(pooled, dict) else None
        return replace(acting, pooled=left)

    def take(self, acting: Acting) -> Acting:
        """In the trainer: the part's acting with its frames copied back in."""
        frames = self._frames.copy()
        pooled = acting.pooled
        return replace(acting, pooled={**pooled, CAMERA: frames} if pooled else frames)

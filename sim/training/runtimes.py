"""Policy runtimes: the numerics a machine's policies drive with, by version.

A race replays exactly only where its policy computes exactly as it did. The libraries
pick their kernels by the CPU: oneDNN's convolutions by its instruction set, OpenBLAS's
matrix products by core type, numpy's ufuncs by its SIMD level, and an ARM machine takes
other kernels again. Their results differ in the last bits (measured on this project's
AMD EPYC: a camera network's outputs under oneDNN's SSE4.1 against AVX2, and a vector
network's under OpenBLAS's Prescott kernels against Haswell's, and under numpy without
AVX2), and a last bit can turn a near tie between two actions, and the race with it.
(Torch's own capability level, DEFAULT against AVX2, changed a fresh network's random
weights here, not a loaded network's outputs.)

So a runtime is named by what it computes: a fixed camera network and a fixed vector
network, run on fixed inputs laid out as races lay them out by the paths races take, and
the bits of their outputs hashed. Two machines with the same name compute a race's policy
the same; a race is recorded with the name, and verification by replay judges a race
only under the runtime that drove it.

The paths themselves are versioned, as the physics is. Every version stays here, so a
race keeps replaying under the one that drove it on any machine that has it:
- version 1, `torch ...`: camera networks in torch (oneDNN), the rest in numpy: every race
  recorded before version 2.
- version 2, `v2 numpy ...`: camera networks in numpy too (`NumpyActor`), about three times
  faster at a batch of one: races and the trainer's evaluations since issue 47.
"""

from __future__ import annotations

import functools
import hashlib
import json
import platform
from typing import Final

import numpy as np
import torch

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata
from sim.sensors.observations import SensorOptions
from sim.training.numpy_policy import NumpyActor, one_blas_thread
from sim.training.policy import build_network, observation_tensors

TORCH_CAMERA: Final = 1
NUMPY_CAMERA: Final = 2
VERSIONS: Final = (TORCH_CAMERA, NUMPY_CAMERA)
CURRENT_RUNTIME: Final = NUMPY_CAMERA

# The camera races use: some kernels are picked by the size of what they work on.
_PROBE_CAMERA = SensorOptions()
_PROBE_ACTIONS = discrete_grid(30.0, 5, 3.0, 2)


def _fill(network: torch.nn.Module) -> None:
    """Fixed weights, the same on every machine: numpy's PCG64 gives the same doubles
    everywhere (torch's own generator does not: its CPU capability changes them)."""
    rng = np.random.Generator(np.random.PCG64(47))
    with torch.no_grad():
        for parameter in network.parameters():
            values = (rng.random(parameter.numel()) - 0.5) * 0.4
            parameter.copy_(torch.from_numpy(values).reshape(parameter.shape).to(parameter.dtype))


def _camera_bits(version: int) -> bytes:
    network = build_network(ModelMetadata(_PROBE_ACTIONS, ("camera",)), _PROBE_CAMERA).eval()
    _fill(network)
    actor = NumpyActor(network) if version == NUMPY_CAMERA else None
    height, width = _PROBE_CAMERA.camera_height, _PROBE_CAMERA.camera_width
    pattern = (np.arange(2 * height * width, dtype=np.int64) * 37 % 251).astype(np.uint8)
    # As the Observer gives them: frames with their one channel added last (stride 0); one
    # car's (a time trial) and two cars' (a head-to-head race's batch).
    bits = b""
    for cars in (1, 2):
        frames = pattern[: cars * height * width].reshape(cars, height, width)[..., None]
        if actor is not None:
            bits += actor.action_parameters(frames).tobytes()
            continue
        with torch.inference_mode():
            params, values = network(observation_tensors(frames))
        bits += params.numpy().tobytes() + values.numpy().tobytes()
    return bits


def _vector_bits() -> bytes:
    network = build_network(ModelMetadata(_PROBE_ACTIONS, ("vector",))).eval()
    _fill(network)
    actor = NumpyActor(network)
    size = int(actor.layers[0][0].shape[0])
    x = np.sin(np.arange(4 * size, dtype=np.float64)).reshape(4, size)
    for weight, bias in actor.layers:
        x = np.tanh(x @ weight + bias)
    out = x @ actor.head[0] + actor.head[1]
    return np.ascontiguousarray(out).tobytes()


def _name(version: int) -> str:
    if version == TORCH_CAMERA:
        # Hashed as runtimes were named before they had versions: version 1's names stay.
        digest = hashlib.sha256(_camera_bits(version) + _vector_bits()).hexdigest()[:12]
        return f"torch {torch.__version__.split('+')[0]} {platform.machine()} {digest}"
    content = f"v{version}".encode() + _camera_bits(version) + _vector_bits()
    digest = hashlib.sha256(content).hexdigest()[:12]
    return f"v{version} numpy {np.__version__} {platform.machine()} {digest}"


@functools.cache
def policy_runtimes() -> dict[int, str]:
    """This machine's name of each runtime version, e.g. `{1: "torch 2.13.0 x86_64
    <12 hex digits>", 2: "v2 numpy 2.3.5 x86_64 <12 hex digits>"}`, the digits a hash of
    the probe networks' output bits, worked out on one thread as policies drive
    (`PolicyDriver`): the thread count is part of the numerics too."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    one_blas_thread()
    try:
        # Building the probes draws torch's random weights: the generator is put back, so
        # a seeded training draws the same numbers whether or not a probe ran first.
        with torch.random.fork_rng(devices=[]):
            return {version: _name(version) for version in VERSIONS}
    finally:
        torch.set_num_threads(threads)


def policy_runtime(version: int = CURRENT_RUNTIME) -> str:
    """This machine's name of runtime `version` (the current one by default)."""
    return policy_runtimes()[version]


def runtime_version(name: str) -> int | None:
    """The version this machine drives as runtime `name`, or None when none does."""
    return next((version for version, here in policy_runtimes().items() if here == name), None)


if __name__ == "__main__":
    # `python -m sim.training.runtimes`: this machine's runtime names as JSON, for a host
    # comparing machines (and the tests that hold each kernel level to its names).
    print(json.dumps(policy_runtimes()))

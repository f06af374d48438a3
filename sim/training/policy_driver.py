"""A trained policy as a race `Driver`, and the drivers of garage models and bundles.

A driver drives with one policy runtime (`sim.training.runtimes`): the current version
for races and the trainer's evaluations, and whichever version drove a recorded race when
verification by replay runs it again (`under`).
"""

from __future__ import annotations

import itertools
import weakref
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from numpy.typing import NDArray

from sim.car_archive.archive import read_car_archive
from sim.car_archive.driver import CarArchiveDriver
from sim.car_archive.errors import CarModelError
from sim.deepracer.files import ModelMetadata
from sim.foundation.remedies import Fix
from sim.garage.folder import ModelError
from sim.physics.simulation import TrackSimulation
from sim.race.driver import Driver, DriverAction
from sim.sensors.observations import Observer, SensorOptions
from sim.training.errors import PolicyError
from sim.training.numpy_policy import NumpyActor, one_blas_thread
from sim.training.policy import PolicyNetwork, load_policy, observation_tensors
from sim.training.runtimes import CURRENT_RUNTIME, TORCH_CAMERA, policy_runtime, runtime_version

if TYPE_CHECKING:
    from sim.garage.bundle import Bundle
    from sim.garage.folder import ModelFolder


def _batched(parts: Sequence[NDArray[Any]]) -> NDArray[Any]:
    """Several cars' observations as one batch, laid out as one car's is. A one-channel
    camera's frames come with their channel axis added last (`Observer`: stride 0), which
    torch pools as a plain NCHW image; concatenated whole, their channel axis had stride 1,
    torch took the batch for channels-last and pooled it 8 times slower (0.34 ms against
    0.04 ms a step in a two-car race)."""
    if parts[0].ndim == 4 and parts[0].shape[-1] == 1:
        return np.concatenate([part[..., 0] for part in parts])[..., None]
    return np.concatenate(parts)


class PolicyDriver:
    """A trained policy as a race `Driver`: deterministic, one action per car.

    Inference calls the network directly (no SB3 `predict` loop), in numpy
    (`NumpyActor`): a 4-minute race with a vector or lidar model simulates in well under a
    second. Under runtime version 1 a camera network runs in torch, as it did then. The
    numpy actor's weights are fixed when the driver is made: the trainer makes one for each
    evaluation, of the weights of the moment.
    """

    def __init__(
        self,
        network: PolicyNetwork,
        metadata: ModelMetadata,
        *,
        name: str,
        content_hash: str,
        sensor_options: SensorOptions | None = None,
        runtime_version: int = CURRENT_RUNTIME,
    ) -> None:
        # A batch of one observation is too small to share between cores: extra threads
        # only add synchronisation (several times slower on a busy 2-core machine),
        # wherever the race runs (the CLI, the app's workers, a league night).
        torch.set_num_threads(1)
        one_blas_thread()
        self.network = network.eval()
        self.version = runtime_version
        in_torch = network.camera is not None and self.version == TORCH_CAMERA
        self._fast = None if in_torch else NumpyActor(network)
        self.metadata = metadata
        self.name = name
        self.content_hash = content_hash
        self._options = sensor_options or SensorOptions()
        # The numerics it drives with: recorded on its races, which verification by replay
        # judges only under the same (`sim.training.runtimes`).
        self.runtime = policy_runtime(self.version)
        # One Observer per simulation it drives in: a head-to-head race gives each car a
        # simulation of its own, and one model may drive several of them.
        self._observers: weakref.WeakKeyDictionary[TrackSimulation, Observer] = (
            weakref.WeakKeyDictionary()
        )

    def under(self, runtime: str) -> PolicyDriver | None:
        """This policy driving with the runtime named `runtime` (a recorded race's), or
        None when this machine has no runtime of that name."""
        version = runtime_version(runtime)
        if version is None:
            return None
        if version == self.version:
            return self
        return PolicyDriver(
            self.network,
            self.metadata,
            name=self.name,
            content_hash=self.content_hash,
            sensor_options=self._options,
            runtime_version=version,
        )

    def reset(self, sim: TrackSimulation) -> None:
        self._observers[sim] = Observer(sim, self.metadata.sensors, self._options)

    def _observe(self, sim: TrackSimulation) -> Any:
        observer = self._observers.get(sim)
        if observer is None:
            self.reset(sim)
            observer = self._observers[sim]
        return observer.observe()

    def _actions_of(self, obs: Any) -> NDArray[Any]:
        if self._fast is not None:
            return self._fast.act(obs)
        with torch.inference_mode():
            actions = self.network.act(observation_tensors(obs))
        return actions.numpy()

    def actions(self, sim: TrackSimulation) -> NDArray[Any]:
        """Raw policy actions for every car: indices, or (N, 2) normalised values."""
        return self._actions_of(self._observe(sim))

    def act(self, sim: TrackSimulation) -> DriverAction:
        return self._driver_action(self.actions(sim))

    def act_many(self, sims: Sequence[TrackSimulation]) -> list[DriverAction]:
        """`act` for several simulations (a head-to-head race's cars of this model), their
        observations in one batch: one forward pass for all of them."""
        observed = [self._observe(sim) for sim in sims]
        if isinstance(observed[0], dict):
            obs: Any = {key: _batched([part[key] for part in observed]) for key in observed[0]}
        else:
            obs = _batched(observed)
        whole = self._driver_action(self._actions_of(obs))
        ends = list(itertools.accumulate(sim.n for sim in sims))
        return [
            DriverAction(
                steering_deg=whole.steering_deg[start:end],
                speed=whole.speed[start:end],
                action_index=whole.action_index[start:end],
            )
            for start, end in itertools.pairwise([0, *ends])
        ]

    def _driver_action(self, actions: NDArray[Any]) -> DriverAction:
        space = self.metadata.action_space
        steering, speed = space.targets(actions)
        if space.kind == "discrete":
            index = np.asarray(actions, dtype=np.int64).reshape(-1)
        else:
            index = np.full(len(actions), -1, dtype=np.int64)
        return DriverAction(
            steering_deg=np.asarray(steering, dtype=np.float64),
            speed=np.asarray(speed, dtype=np.float64),
            action_index=index,
        )


def driver_for_model(folder: ModelFolder) -> Driver:
    """The driver for a garage model's `policy.safetensors`, or for the car archive it was
    imported from (`sim.car_export`)."""
    if folder.drives_with_car_archive():
        try:
            archive = read_car_archive(folder.car_archive_file)
            return CarArchiveDriver(archive, name=folder.name, content_hash=folder.content_hash())
        except CarModelError as error:
            raise ModelError(f"model {folder.name!r}: {error}") from None
    if not folder.has_policy():
        problem = f"model {folder.name!r} has no trained policy yet"
        raise PolicyError(
            f"{problem}; train it first with `racer-tui train {folder.name}`.",
            problem=problem,
            fix=Fix.TRAIN_MODEL,
        )
    metadata = folder.metadata()
    network = load_policy(folder.policy_file, metadata)
    return PolicyDriver(network, metadata, name=folder.name, content_hash=folder.content_hash())


def driver_for_bundle(bundle: Bundle) -> PolicyDriver:
    """The driver for an exported model bundle (its tensors only; nothing is executed)."""
    network = load_policy(bundle.policy_bytes, bundle.metadata)
    return PolicyDriver(
        network, bundle.metadata, name=bundle.name, content_hash=bundle.content_hash
    )

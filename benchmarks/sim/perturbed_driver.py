"""A trained policy driving through a chosen camera perturbation: how the sim-to-real
benchmark evaluates models on pictures they never trained on.

Races and evaluations drive on the plain render; this driver is for callers that ask for
another picture explicitly. Every car of the simulation sees through the same perturbation
(its sensor noise differs from frame to frame). torch is imported by the policy module this
builds on, when a driver is made.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from numpy.typing import NDArray

from sim.physics.simulation import TrackSimulation
from sim.sensors.observations import Observer
from sim.sensors.randomisation.perturbation import CameraPerturbation

if TYPE_CHECKING:
    from sim.garage.folder import ModelFolder
    from sim.training.policy_driver import PolicyDriver


def perturbed_driver(
    folder: ModelFolder, perturbation: CameraPerturbation, *, noise_seed: int = 0
) -> PolicyDriver:
    """The driver of a garage model's policy whose camera sees through `perturbation`."""
    from sim.training.policy import load_policy
    from sim.training.policy_driver import PolicyDriver

    class PerturbedPolicyDriver(PolicyDriver):
        """`PolicyDriver` whose observations come through a perturbed camera."""

        _seen: Observer | None = None

        def reset(self, sim: TrackSimulation) -> None:
            self._seen = Observer(sim, self.metadata.sensors)
            self._seen.perturb_camera(
                list(range(sim.n)), [perturbation] * sim.n, noise_seed=noise_seed
            )

        def actions(self, sim: TrackSimulation) -> NDArray[Any]:
            import torch

            from sim.training.policy import observation_tensors

            if self._seen is None or self._seen.sim is not sim:
                self.reset(sim)
            assert self._seen is not None
            with torch.inference_mode():
                chosen = self.network.act(observation_tensors(self._seen.observe()))
            return chosen.numpy()

    metadata = folder.metadata()
    network = load_policy(folder.policy_file, metadata)
    return PerturbedPolicyDriver(
        network, metadata, name=folder.name, content_hash=folder.content_hash()
    )

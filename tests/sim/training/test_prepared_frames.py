"""A training pools its camera frames in numpy (`pooled_frames`) once a step, for acting
and for the rollout buffer the update reads: within a float32 unit of the network's own
pooling, which races keep, and the same inputs for acting and for the update."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from sim.training import actor
from sim.training.policy import PolicyNetwork, pooled_frames
from tests.sim.training.rollouts import collected

FLOAT32_UNIT = float(np.finfo(np.float32).eps)


@pytest.mark.parametrize("shape", [(5, 120, 160, 1), (3, 61, 81, 1), (2, 4, 8, 6, 1)])
def test_pooled_frames_are_the_networks_pooling_within_a_float32_unit(
    shape: tuple[int, ...],
) -> None:
    frames = np.random.default_rng(7).integers(0, 256, shape, dtype=np.uint8)
    flat = frames.reshape(-1, *shape[-3:])
    network = PolicyNetwork.__new__(PolicyNetwork)  # only its first layer is used
    torch.nn.Module.__init__(network)
    network.camera = torch.nn.Sequential(torch.nn.AvgPool2d(2))
    with torch.no_grad():
        reference = network.camera_frames(torch.from_numpy(flat)).permute(0, 2, 3, 1).numpy()
    for given in (frames, frames.astype(np.float32)):  # the Observer's, the buffer's
        pooled = pooled_frames(given)
        assert pooled.dtype == np.float32
        assert pooled.shape == (*shape[:-3], shape[-3] // 2, shape[-2] // 2, 1)
        np.testing.assert_allclose(
            pooled.reshape(reference.shape), reference, rtol=0, atol=1.5 * FLOAT32_UNIT
        )
    pixel = np.zeros((1, 2, 2, 1), dtype=np.uint8)
    pixel[0, :, :, 0] = [[255, 255], [0, 1]]
    assert float(pooled_frames(pixel)[0, 0, 0, 0]) == pytest.approx(511 / 1020, abs=FLOAT32_UNIT)


@pytest.mark.parametrize("sensors", [("camera",), ("camera", "lidar")])
def test_the_update_reads_the_inputs_acting_read(sensors: tuple[str, ...]) -> None:
    """The log-probabilities the update computes before its first step are the ones the
    collection stored: the same frames, pooled the same way."""
    torch.manual_seed(3)
    np.random.seed(3)
    model = collected(sensors, batch_size=16)
    buffer = model.rollout_buffer
    with actor.training_mode(model.network, model.bf16_training):  # as acting ran it
        batch = next(buffer.get(None))
        with torch.no_grad():
            _, log_prob, _ = model.policy.evaluate_actions(
                batch.observations, batch.actions.long().flatten()
            )
        camera = buffer.observations["camera"] if len(sensors) > 1 else buffer.observations
        assert camera.shape[-3:] == (60, 80, 1)  # kept pooled: a quarter of the raw frames
    # Batches of other sizes may round their last bit otherwise.
    torch.testing.assert_close(log_prob, batch.old_log_prob, rtol=0, atol=1e-6)
    # Races read the Observer's frames again, in float32.
    assert not model.network.frames_prepared and not model.network.bf16_convolutions

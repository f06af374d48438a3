"""The PPO update takes a camera model's minibatches in slices, and its convolutions in
bfloat16 on CPUs that have it: the slices must add up to the whole minibatch's update, and
the bfloat16 must stay inside a training."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pytest
import torch

from sim.reward import guard as reward_guard
from sim.training import actor, ppo_loss
from sim.training.minibatch_shares import MinibatchShares
from sim.training.ppo import RacerPPO
from sim.training.ppo_loss import LossSettings, Minibatch, normalized_advantages, slice_loss
from tests.sim.training.rollouts import collected

SENSORS = ("camera", "lidar")


def _collected() -> RacerPPO:
    torch.manual_seed(5)
    np.random.seed(5)
    return collected(SENSORS, batch_size=24)


def _updated(
    monkeypatch: pytest.MonkeyPatch, slices: int, bf16: bool = False, threads: int = 1
) -> Any:
    model = _collected()
    model.bf16_training = bf16
    model.update_threads = threads
    monkeypatch.setattr(ppo_loss, "CAMERA_SLICE_SAMPLES", slices)
    monkeypatch.setattr(ppo_loss, "CAMERA_SLICE_SAMPLES_BF16", slices)
    np.random.seed(6)
    model.train()
    weights = {name: value.detach().clone() for name, value in model.network.state_dict().items()}
    return weights, model.last_update, model


def _first_minibatch(model: RacerPPO, size: int, settings: LossSettings) -> Minibatch:
    batch = next(model.rollout_buffer.get(size))
    return Minibatch.of(
        batch.observations,
        actions=batch.actions,
        old_log_prob=batch.old_log_prob,
        advantages=normalized_advantages(batch.advantages, settings.normalize_advantage),
        returns=batch.returns,
        discrete=settings.discrete,
    )


def test_a_minibatch_in_slices_makes_the_update_of_the_whole_minibatch(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    whole, whole_figures, _ = _updated(monkeypatch, slices=24)
    sliced, sliced_figures, _ = _updated(monkeypatch, slices=5)  # 24 = 5+5+5+5+4
    for name, value in whole.items():
        # Only the order of float additions differs.
        torch.testing.assert_close(sliced[name], value, rtol=1e-4, atol=1e-6)
    fresh = _collected().network.state_dict()
    moved = sum(int(not torch.equal(fresh[name], value)) for name, value in whole.items())
    assert moved == len(whole)  # the update did change every tensor it compares
    for field in ("entropy", "policy_loss", "value_loss", "approx_kl", "clip_fraction"):
        assert getattr(sliced_figures, field) == pytest.approx(
            getattr(whole_figures, field), rel=1e-4, abs=1e-7
        )


def test_the_slices_shares_of_the_loss_add_up_to_the_minibatchs_mean_loss() -> None:
    model = _collected()
    settings = LossSettings(0.2, 0.01, 0.5, "huber", normalize_advantage=False, discrete=True)
    samples = _first_minibatch(model, 20, settings)
    evaluate = model.policy.evaluate_actions
    with torch.no_grad(), actor.training_mode(model.network, bf16=False):
        whole, whole_figures = slice_loss(evaluate, samples, 20, settings)
        first, first_figures = slice_loss(evaluate, samples.part(0, 7), 20, settings)
        rest, rest_figures = slice_loss(evaluate, samples.part(7, 20), 20, settings)
        values, _, _ = evaluate(samples.observations, samples.actions)
    assert float(first + rest) == pytest.approx(float(whole), rel=1e-5)
    np.testing.assert_allclose(first_figures + rest_figures, whole_figures, rtol=1e-5, atol=1e-8)
    huber = torch.nn.functional.smooth_l1_loss(values.flatten(), samples.returns)
    assert whole_figures[2] == pytest.approx(float(huber), rel=1e-5)  # the minibatch's mean


def test_bfloat16_convolutions_stay_inside_a_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """Forced on (whatever this CPU has): the update stays close to float32's, and after it
    the network acts in float32 again, as races and replays need."""
    exact, _, _ = _updated(monkeypatch, slices=8)
    low, _, model = _updated(monkeypatch, slices=8, bf16=True)
    network = model.network
    assert not network.bf16_convolutions
    changed = [name for name in exact if not torch.equal(exact[name], low[name])]
    assert changed  # bfloat16 really ran
    for name in exact:
        torch.testing.assert_close(low[name], exact[name], rtol=0.1, atol=2e-3)
    camera, lidar = network.spec.input_shapes
    frames = (torch.rand(3, *camera) * 255).to(torch.uint8)
    obs = {"camera": frames, "lidar": torch.rand(3, *lidar)}
    with torch.no_grad():
        float32 = network.features(obs)
        network.bf16_convolutions = True
        bf16 = network.features(obs)
    assert float32.dtype == bf16.dtype == torch.float32
    assert not torch.equal(float32, bf16)
    torch.testing.assert_close(bf16, float32, rtol=0.05, atol=0.02)


@pytest.mark.parametrize("slices", [5, 64])  # shares of 15 and 9; of 12 and 12
def test_a_minibatch_in_shares_on_threads_makes_the_update_of_one_thread(
    monkeypatch: pytest.MonkeyPatch, slices: int
) -> None:
    one, one_figures, _ = _updated(monkeypatch, slices=slices)
    threads: set[int] = set()
    guarded: set[bool] = set()
    real = ppo_loss.slice_loss

    def noting_the_thread(*args: Any, **kwargs: Any) -> Any:
        threads.add(threading.get_ident())
        guarded.add(
            threading.current_thread() is threading.main_thread()
            or reward_guard.is_own_thread(threading.get_ident())
        )
        return real(*args, **kwargs)

    monkeypatch.setattr(ppo_loss, "slice_loss", noting_the_thread)
    two, two_figures, _ = _updated(monkeypatch, slices=slices, threads=2)
    assert len(threads) == 2  # both shares of each minibatch ran, each in its own thread
    assert guarded == {True}  # the reward guard never takes the update's thread for racer code
    for name, value in one.items():
        # Only the order of float additions differs.
        torch.testing.assert_close(two[name], value, rtol=1e-4, atol=1e-6)
    for field in ("entropy", "policy_loss", "value_loss", "approx_kl", "clip_fraction"):
        assert getattr(two_figures, field) == pytest.approx(
            getattr(one_figures, field), rel=1e-4, abs=1e-7
        )
    assert torch.get_num_threads() == 1  # collection's forward passes stay on one thread


def test_shares_outside_their_threads_are_all_computed_in_the_calling_thread() -> None:
    model = _collected()
    settings = LossSettings(0.2, 0.01, 0.5, "huber", normalize_advantage=True, discrete=True)
    samples = _first_minibatch(model, 24, settings)
    network = model.network
    gradients: list[list[torch.Tensor | None]] = []
    figures = []
    with actor.training_mode(network, bf16=False):
        for threads in (1, 2):
            shares = MinibatchShares(network, model.policy.action_dist, threads)
            figures.append(shares.gradients(samples, settings, at_a_time=5))
            gradients.append([value.grad for value in network.parameters()])
    reached = [(one, two) for one, two in zip(*gradients, strict=True) if one is not None]
    assert reached and all(two is not None for _, two in reached)
    for one, two in reached:
        torch.testing.assert_close(two, one, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(figures[1], figures[0], rtol=1e-4, atol=1e-8)

"""A camera minibatch's gradient in shares computed side by side, one thread each.

A training on N processes has N cores for its update: the simulation processes wait while
it runs. torch's own threads split each operator of the update, and a camera network's
smallest layers are memory traffic: on two threads the update ran at 1.4-1.6x one thread
(docs/camera-learner-profile.md). Here each thread takes a whole share of the minibatch
instead, through the same network, with torch's one-thread kernels: on a 2-core AMD EPYC
the same training's updates ran at 1.7x one thread this way, against 1.37x on torch's two
threads.

Each share's gradient comes from `torch.autograd.grad`, so no thread writes another's
gradients, and the shares' gradients are added in the shares' order: the sum does not
depend on which thread finished first. A share is the slices `ppo_loss.share_gradients`
takes, so one thread computes exactly what the update computed before threads.

The threads live for one update (starting one costs far less than a minibatch): they are
started after the training process is contained, inherit its limits, and end with the
update. They run no racer code, so the reward guard counts them as racer-tui's own.
"""

from __future__ import annotations

import copy
import functools
import threading
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager

import numpy as np
import torch
from stable_baselines3.common.distributions import Distribution

from sim.reward import guard as reward_guard
from sim.training.policy import PolicyNetwork
from sim.training.ppo_loss import (
    LossSettings,
    Minibatch,
    add_gradients,
    evaluate_actions,
    share_gradients,
)

THREAD_NAME = "racer-tui-update"

Gradients = list[torch.Tensor | None]


class MinibatchShares:
    """Computes minibatch gradients of `network` in `threads` shares, within `running`."""

    def __init__(self, network: PolicyNetwork, template: Distribution, threads: int) -> None:
        self.network = network
        self.threads = max(1, threads)
        # A distribution object keeps the last distribution it made (assigned, never changed
        # in place): a shallow copy per share keeps the shares' apart.
        self._templates = [template, *(copy.copy(template) for _ in range(self.threads - 1))]
        self._parameters = [value for value in network.parameters() if value.requires_grad]
        self._pool: ThreadPoolExecutor | None = None

    @contextmanager
    def running(self) -> Iterator[MinibatchShares]:
        """The shares' threads, for one update."""
        if self.threads == 1:
            yield self
            return
        with ThreadPoolExecutor(
            self.threads - 1, thread_name_prefix=THREAD_NAME, initializer=_own_thread
        ) as pool:
            self._pool = pool
            try:
                yield self
            finally:
                self._pool = None

    def gradients(
        self, samples: Minibatch, settings: LossSettings, at_a_time: int | None
    ) -> np.ndarray:
        """Set the parameters' gradients to those of `samples`' mean loss (the whole
        minibatch); its `ppo_loss.FIGURES`."""
        size = len(samples)
        parts = [
            samples.part(start, end) for start, end in _share_bounds(size, self.threads, at_a_time)
        ]
        futures: list[Future[tuple[Gradients, np.ndarray]]] = []
        if self._pool is not None:
            futures = [
                self._pool.submit(self._share, index, part, size, settings, at_a_time)
                for index, part in enumerate(parts[1:], start=1)
            ]
        # This thread's share, or outside `running` every share, one after another.
        here = parts[: len(parts) - len(futures)]
        results = [
            self._share(index, part, size, settings, at_a_time) for index, part in enumerate(here)
        ]
        results += [future.result() for future in futures]
        # The shares added into the first, in the shares' order.
        gradients, figures = results[0]
        for more, share_figures in results[1:]:
            add_gradients(gradients, more)
            figures += share_figures
        for parameter, gradient in zip(self._parameters, gradients, strict=True):
            parameter.grad = gradient
        return figures

    def _share(
        self,
        index: int,
        samples: Minibatch,
        size: int,
        settings: LossSettings,
        at_a_time: int | None,
    ) -> tuple[Gradients, np.ndarray]:
        evaluate = functools.partial(evaluate_actions, self.network, self._templates[index])
        return share_gradients(
            evaluate, samples, size, settings, at_a_time=at_a_time, parameters=self._parameters
        )


def _share_bounds(size: int, shares: int, at_a_time: int | None) -> list[tuple[int, int]]:
    """`size` samples in `shares` contiguous runs as even as whole slices of `at_a_time`
    allow (so one share is the slices a single thread takes), or as even as samples allow
    where the minibatch has fewer slices than shares (DeepRacer's batch of 64, say); never an
    empty share but the first."""
    unit = at_a_time or 1
    slices = -(-size // unit)
    if slices < shares:
        unit, slices = 1, size
    count = max(1, min(shares, slices))
    per, larger = divmod(slices, count)
    bounds, first = [], 0
    for index in range(count):
        end = min(size, first + (per + (1 if index < larger else 0)) * unit)
        bounds.append((first, end))
        first = end
    return bounds


def _own_thread() -> None:
    reward_guard.own_thread(threading.current_thread().name)

"""A training fleet spread across processes, one learner: training on every core.

deepracer-for-cloud trains with several simulation workers feeding one learner; racer-tui
does the same within one machine. The fleet's cars are split into parts: the trainer's
process steps the first part itself, and each other part runs in a simulation process of
its own (its own pymunk space, its own reward modules, its own reward time limit). A step
sends each process its cars' actions, steps the trainer's own part meanwhile, and gathers
the others' observations, rewards and ended episodes (`sim.training.step_record`) in the
cars' order, so the learner and the training log see one fleet:

- a part's cars start where the same cars of one whole fleet would (`first_car`,
  `fleet_cars`), so with the same actions a split fleet of a time trial without camera
  randomisation steps, and is logged, exactly as the whole one;
- its boxes and bots, and its camera draws, are seeded from its first car, so the parts
  meet different ones (and a split fleet among them is not the whole one's draw);
- episodes are numbered, metered and traced by the trainer's one `Logbook`.

Where it stops scaling: every step waits for the slowest part (parts are kept even), the
policy's forward pass for the whole fleet and the PPO update run in the trainer's process
alone, and each step pickles the parts' observations through a pipe (a camera frame is
19 kB a car). A simulation process builds its own config from the model folder, as a
DRfC worker reads the model from its bucket: nothing but the folder's path, numbers and
actions crosses the pipe to it, and only plain data comes back.

A simulation process ends when the trainer closes it, and on its own when the trainer's
end of the pipe closes (the trainer died): it never outlives a training.
"""

from __future__ import annotations

import contextlib
import multiprocessing
from collections.abc import Callable
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import numpy as np

from sim.env import BatchedDeepRacer, EnvConfig
from sim.training.fleet_parts import (
    PartError,
    PartSetup,
    PartStep,
    serve_part,
    split_fleet,
)
from sim.training.step_record import EndedEpisode, StepRecorder
from sim.training.vec_env import FleetVecEnv, sb3_infos

JOIN_SECONDS = 5.0


class ShardedVecEnv(FleetVecEnv):
    """A fleet of `cars` cars of `config` over `processes` processes (this one included).

    `folder` is the model folder the config was read from (the other processes read it
    again); `record` keeps every step's rows and hands each step's ended episodes, in the
    cars' order, to `on_step` (the trainer's `Logbook.add_step`)."""

    def __init__(
        self,
        config: EnvConfig,
        folder: Path,
        cars: int,
        processes: int,
        *,
        seed: int | None = None,
        on_step: Callable[[list[EndedEpisode]], None] | None = None,
        reward_seconds: float | None = None,
        opponents: tuple[str, ...] = (),
    ) -> None:
        self.config = config
        self.parts = split_fleet(cars, processes)
        self._on_step = on_step
        discrete = config.action_space.kind == "discrete"
        own = self.parts[0]
        self.batch = BatchedDeepRacer(config, own.cars, seed, first_car=0, fleet_cars=cars)
        self._recorder: StepRecorder | None = None
        if on_step is not None:
            self._recorder = StepRecorder(own.cars, discrete=discrete)
            self.batch.watcher = self._recorder
        self._remotes: list[_Remote] = []
        try:
            for part in self.parts[1:]:
                setup = PartSetup(
                    folder=str(folder),
                    part=part,
                    fleet_cars=cars,
                    seed=None if seed is None else seed + part.first_car,
                    record=on_step is not None,
                    discrete=discrete,
                    reward_seconds=reward_seconds,
                    opponents=opponents,
                )
                self._remotes.append(_Remote.start(setup))
            for remote in self._remotes:
                remote.receive()  # "ready", or the part's error raised here
        except BaseException:
            self.close()
            raise
        super().__init__(cars, self.batch.observation_space, self.batch.action_space)
        self._actions: np.ndarray | None = None
        self.last_infos = []

    @property
    def processes(self) -> int:
        return len(self.parts)

    @property
    def pids(self) -> list[int]:
        """The simulation processes' (this one's not included)."""
        return [remote.process.pid for remote in self._remotes]

    def reset(self) -> Any:
        for remote in self._remotes:
            remote.send(("reset", None))
        own = self.batch.reset()
        return _joined([own, *(remote.receive() for remote in self._remotes)])

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions
        for remote, part in zip(self._remotes, self.parts[1:], strict=True):
            remote.send(("step", actions[part.first_car : part.first_car + part.cars]))

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        assert self._actions is not None, "step_async must come first"
        own_cars = self.parts[0].cars
        own = self.batch.step(self._actions[:own_cars])
        results = [PartStep.of(self.batch, own, self._recorder)]
        results += [remote.receive() for remote in self._remotes]
        self.last_infos = [info for result in results for info in result.infos]
        if self._on_step is not None:
            self._on_step([episode for result in results for episode in result.ended])
        dones = np.concatenate([r.terminated | r.truncated for r in results])
        truncated_all = np.concatenate([r.truncated for r in results])
        finals: list[Any] = [None] * self.num_envs
        for result, part in zip(results, self.parts, strict=True):
            for car, final in result.finals.items():
                finals[part.first_car + car] = final
        rewards_all = np.concatenate([r.rewards for r in results]).astype(np.float32)
        return (
            _joined([r.obs for r in results]),
            rewards_all,
            dones,
            sb3_infos(dones, truncated_all, finals),
        )

    def close(self) -> None:
        """End the simulation processes (waiting a little for each, then terminating)."""
        for remote in self._remotes:
            remote.stop()
        self._remotes = []


class _Remote:
    """The trainer's end of one simulation process."""

    def __init__(self, process: Any, connection: Connection) -> None:
        self.process = process
        self.connection = connection

    @classmethod
    def start(cls, setup: PartSetup) -> _Remote:
        # spawn, not fork: the trainer has torch's threads running, which fork would copy
        # half-alive into the child.
        context = multiprocessing.get_context("spawn")
        ours, theirs = context.Pipe()
        process = context.Process(
            target=serve_part, args=(theirs, setup), name="racer-tui-sim", daemon=True
        )
        process.start()
        theirs.close()  # the child holds its end: our copy would hide its death from us
        return cls(process, ours)

    def send(self, message: tuple[str, Any]) -> None:
        try:
            self.connection.send(message)
        except (BrokenPipeError, ConnectionResetError, OSError):
            raise PartError(self._gone()) from None

    def receive(self) -> Any:
        try:
            kind, value = self.connection.recv()
        except (EOFError, ConnectionResetError, OSError):
            raise PartError(self._gone()) from None
        if kind == "error":
            raise value
        return value

    def _gone(self) -> str:
        self.process.join(JOIN_SECONDS)
        code = self.process.exitcode
        return (
            f"a simulation process of this training ended unexpectedly (exit code {code}); "
            "start the training again, with --processes 1 if it keeps happening"
        )

    def stop(self) -> None:
        with contextlib.suppress(BrokenPipeError, ConnectionResetError, OSError):
            self.connection.send(("close", None))
        self.connection.close()
        self.process.join(JOIN_SECONDS)
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(JOIN_SECONDS)


def _joined(parts: list[Any]) -> Any:
    """The parts' observations as one fleet's (a dict of arrays per sensor, or one array)."""
    if len(parts) == 1:
        return parts[0]
    if isinstance(parts[0], dict):
        return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
    return np.concatenate(parts)

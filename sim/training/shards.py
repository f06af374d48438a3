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

Acting: for a camera model, each simulation process acts for its own cars with a copy of
the policy (sim.training.actor), the weights sent at the start of each rollout, so the
forward passes run on every core; for other sensors the trainer acts for the whole fleet
(its network is small) and the simulation processes stay free of torch.

Where it stops scaling: every step waits for the slowest part (parts are kept even), the
PPO update runs in the trainer's process alone, and each step pickles the parts'
observations through a pipe (a camera frame is 19 kB a car; a part that acts hands its
pooled frames over in shared memory instead, sim.training.shared_frames). A simulation
process builds its own config from the model folder, as a DRfC worker reads the model from
its bucket: nothing but the folder's path, numbers, actions and the policy's weights
crosses the pipe to it, and only plain data comes back.

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
from gymnasium import spaces

from sim.env import BatchedDeepRacer, EnvConfig
from sim.training.acting import Acting, joined_observations
from sim.training.actor import ActorSetup, PolicyActor
from sim.training.fleet_parts import (
    PartError,
    PartSetup,
    PartStep,
    serve_part,
    split_fleet,
)
from sim.training.policy import pooled_frame_shape
from sim.training.shared_frames import SharedFrames
from sim.training.step_record import EndedEpisode, StepRecorder
from sim.training.vec_env import FleetVecEnv, sb3_infos

JOIN_SECONDS = 5.0


class ShardedVecEnv(FleetVecEnv):
    """A fleet of `cars` cars of `config` over `processes` processes (this one included).

    `folder` is the model folder the config was read from (the other processes read it
    again); `record` keeps every step's rows and hands each step's ended episodes, in the
    cars' order, to `on_step` (the trainer's `Logbook.add_step`); with `acting`, the
    simulation processes act for their cars in `step_and_act`."""

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
        acting: ActorSetup | None = None,
    ) -> None:
        self.config = config
        self._remote_acting = acting is not None
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
        # Parts that act for their cars hand their pooled frames over in shared memory.
        frames_shape = None if acting is None else _pooled_camera(self.batch.observation_space)
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
                    acting=acting,
                )
                frames = None if frames_shape is None else (part.cars, frames_shape)
                self._remotes.append(_Remote.start(setup, frames))
            for remote in self._remotes:
                remote.receive()  # "ready", or the part's error raised here
        except BaseException:
            self.close()
            raise
        super().__init__(cars, self.batch.observation_space, self.batch.action_space)
        self._actions: np.ndarray | None = None
        self._own_latest: Any = None  # this process's cars' current observations
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
        self._own_latest = self.batch.reset()
        self.latest = joined_observations(
            [self._own_latest, *(remote.receive() for remote in self._remotes)]
        )
        return self.latest

    def act(self, actor: PolicyActor) -> Acting:
        if not self._remote_acting:
            return super().act(actor)
        weights = actor.weights()
        for remote in self._remotes:
            remote.send(("act", weights))
        own = actor.act(self._own_latest)
        return Acting.joined([own, *(remote.receive_acting() for remote in self._remotes)])

    def step_and_act(
        self, acting: Acting, actor: PolicyActor
    ) -> tuple[np.ndarray, np.ndarray, Acting]:
        if not self._remote_acting:
            return super().step_and_act(acting, actor)
        actions = acting.env_actions(self.config.action_space.kind == "discrete")
        own = self._own_step(actions, "step_act")
        self.latest = None  # the other parts' observations stay in their processes
        own_acting = actor.act(own.obs, own.truncated_finals())
        results = [own, *(remote.receive() for remote in self._remotes)]
        _, rewards, dones = self._gathered(results)
        parts = [own_acting]
        for remote, result in zip(self._remotes, results[1:], strict=True):
            assert result.acting is not None, "every simulation process acts"
            parts.append(remote.with_frames(result.acting))
        return rewards, dones, Acting.joined(parts)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        assert self._actions is not None, "step_async must come first"
        results = [self._own_step(self._actions, "step")]
        results += [remote.receive() for remote in self._remotes]
        truncated, rewards, dones = self._gathered(results)
        finals: list[Any] = [None] * self.num_envs
        for result, part in zip(results, self.parts, strict=True):
            for car, final in result.finals.items():
                finals[part.first_car + car] = final
        self.latest = joined_observations([r.obs for r in results])
        return self.latest, rewards, dones, sb3_infos(dones, truncated, finals)

    def _own_step(self, actions: np.ndarray, kind: str) -> PartStep:
        """Send each simulation process its cars' actions (a message of `kind`), then step
        this process's cars meanwhile."""
        for remote, part in zip(self._remotes, self.parts[1:], strict=True):
            remote.send((kind, actions[part.first_car : part.first_car + part.cars]))
        own = self.batch.step(actions[: self.parts[0].cars])
        step = PartStep.of(self.batch, own, self._recorder)
        self._own_latest = step.obs
        return step

    def _gathered(self, results: list[PartStep]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The parts' step as one fleet's: its infos noted and its ended episodes logged;
        which cars the step limit cut, the rewards (float32) and which cars' episodes
        ended."""
        self.last_infos = [info for result in results for info in result.infos]
        if self._on_step is not None:
            self._on_step([episode for result in results for episode in result.ended])
        truncated = np.concatenate([r.truncated for r in results])
        dones = np.concatenate([r.terminated for r in results]) | truncated
        rewards = np.concatenate([r.rewards for r in results]).astype(np.float32)
        return truncated, rewards, dones

    def close(self) -> None:
        """End the simulation processes (waiting a little for each, then terminating)."""
        for remote in self._remotes:
            remote.stop()
        self._remotes = []


class _Remote:
    """The trainer's end of one simulation process."""

    def __init__(self, process: Any, connection: Connection, frames: SharedFrames | None) -> None:
        self.process = process
        self.connection = connection
        self.frames = frames  # where the part puts its pooled frames, if it acts

    @classmethod
    def start(cls, setup: PartSetup, frames: tuple[int, tuple[int, ...]] | None) -> _Remote:
        """Start the part's process; `frames`: (cars, a pooled frame's shape) when it acts."""
        # spawn, not fork: the trainer has torch's threads running, which fork would copy
        # half-alive into the child.
        context = multiprocessing.get_context("spawn")
        shared = None if frames is None else SharedFrames.allocate(context, *frames)
        ours, theirs = context.Pipe()
        process = context.Process(
            target=serve_part, args=(theirs, setup, shared), name="racer-tui-sim", daemon=True
        )
        process.start()
        theirs.close()  # the child holds its end: our copy would hide its death from us
        return cls(process, ours, shared)

    def receive_acting(self) -> Acting:
        """The part's answer to "act", its frames copied in."""
        return self.with_frames(self.receive())

    def with_frames(self, acting: Acting) -> Acting:
        assert self.frames is not None, "the part was set up without acting"
        return self.frames.take(acting)

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


def _pooled_camera(space: Any) -> tuple[int, ...]:
    """A car's pooled camera frame's shape (parts act only for networks that read a
    camera: sim.training.trainer)."""
    camera = space.spaces["camera"] if isinstance(space, spaces.Dict) else space
    assert camera.shape is not None and camera.dtype == np.uint8, "acting parts read a camera"
    return pooled_frame_shape(camera.shape)

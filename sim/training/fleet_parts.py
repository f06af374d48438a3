"""One part of a training fleet in a process of its own: what it is, how it is set up, and
the simulation process's life (sim.training.shards joins the parts into one fleet).

Torch-free on purpose: a simulation process imports this module and the simulator, and
torch (a second or more of start-up, and hundreds of megabytes) only where it acts for its
cars: a camera model's training, whose forward passes are worth a core's share
(sim.training.actor).
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
import traceback
from dataclasses import dataclass, replace
from multiprocessing.connection import Connection
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sim.env import BatchedDeepRacer, StepInfo
from sim.foundation.remedies import RemedyError
from sim.garage.folder import ModelFolder
from sim.reward import guard as reward_guard
from sim.reward import sandbox as reward_sandbox
from sim.training.acting import Acting
from sim.training.config import training_env_config
from sim.training.opponents import with_opponents
from sim.training.shared_frames import SharedFrames
from sim.training.step_record import EndedEpisode, StepRecorder

if TYPE_CHECKING:
    from sim.training.actor import ActorSetup, PolicyActor


def usable_cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


# More processes than this stop paying before the cores run out: every step waits for the
# slowest part and the learner's share grows (sim.training.shards).
MOST_DEFAULT_PROCESSES = 8


def default_processes() -> int:
    """Simulation processes for a training: the cores less one, left for the app (at most
    MOST_DEFAULT_PROCESSES; `--processes` asks for more)."""
    return max(1, min(usable_cores() - 1, MOST_DEFAULT_PROCESSES))


@dataclass(frozen=True)
class FleetPart:
    """Cars `first_car` .. `first_car + cars - 1` of the fleet."""

    first_car: int
    cars: int


def split_fleet(cars: int, processes: int) -> list[FleetPart]:
    """`cars` in `processes` parts as even as they come (the first ones one car larger);
    never more parts than cars."""
    if cars < 1 or processes < 1:
        raise ValueError("a fleet needs at least one car and one process")
    count = min(cars, processes)
    size, larger = divmod(cars, count)
    parts, first = [], 0
    for index in range(count):
        part = size + (1 if index < larger else 0)
        parts.append(FleetPart(first, part))
        first += part
    return parts


@dataclass(frozen=True)
class PartSetup:
    """What a simulation process needs to build its part (plain data: it is pickled)."""

    folder: str  # the model folder: the process reads its config from there
    part: FleetPart
    fleet_cars: int
    seed: int | None
    record: bool  # keep step rows for the training log
    discrete: bool
    reward_seconds: float | None  # the reward call limit to install; None: none
    opponents: tuple[str, ...] = ()  # cars each training car races (sim.training.opponents)
    acting: ActorSetup | None = None  # the process acts for its cars (None: the trainer does)


# What a part's own forward passes may add to its process's memory besides the reward's
# budget: a step's activations are a few MB for a fleet's cars; the rest is headroom for
# torch's own buffers.
ACTING_MB = 256


@dataclass
class PartStep:
    """One part's step, as the trainer joins it with the others."""

    obs: Any
    rewards: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    infos: list[StepInfo]
    finals: dict[int, Any]  # the final observation of each car whose episode ended
    ended: list[EndedEpisode]
    acting: Acting | None = None  # the part's acting on `obs`, where the part acts

    def truncated_finals(self) -> dict[int, Any]:
        """The final observations of the cars whose episodes the step limit cut."""
        return {car: final for car, final in self.finals.items() if self.truncated[car]}

    def acted_on(self, actor: PolicyActor, frames: SharedFrames) -> PartStep:
        """The step with the part's acting on it, to send without the observations: the
        acting's pooled frames go through `frames`, and the trainer needs no others."""
        acting = frames.put(actor.act(self.obs, self.truncated_finals()))
        return replace(self, obs=None, finals={}, acting=acting)

    @classmethod
    def of(cls, batch: BatchedDeepRacer, step: Any, recorder: StepRecorder | None) -> PartStep:
        obs, rewards, terminated, truncated, infos = step
        ended = np.flatnonzero(terminated | truncated).tolist()
        finals = {car: batch.final_observations[car] for car in ended}
        taken = recorder.take() if recorder is not None else []
        return cls(obs, rewards, terminated, truncated, infos, finals, taken)


class PartError(RemedyError):
    """A simulation process failed in a way that could not be sent as its own error, or
    ended; `str()` is one sentence for the racer."""


def serve_part(connection: Connection, setup: PartSetup, frames: SharedFrames | None) -> None:
    """A simulation process's life: build the part, then answer reset and step until told
    to close or until the trainer's end of the pipe closes. It runs the racer's reward
    function, contained (sim.reward.sandbox): a memory limit, no process, thread or signal
    from a reward call, Landlock (read Python's files and the model's folder, write
    nowhere), and whatever is left under it ends with it. Where it acts for its cars, its
    pooled frames go to the trainer through `frames`."""
    # Ctrl+C in a terminal reaches the whole process group: the trainer decides when its
    # parts stop, and closes them.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # What a reward function prints goes to stderr (the training's log), never to a pipe.
    sys.stdout.flush()
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    reward_sandbox.become_subreaper()
    reward_guard.guard_reward_calls()
    memory_mb = reward_sandbox.memory_from_environment()
    reward_sandbox.set_memory_budget(memory_mb)  # held to while the file loads
    try:
        try:
            batch, recorder = _build_part(connection, setup)
            actor = None if setup.acting is None or frames is None else _actor(setup, batch)
            status = reward_sandbox.close_off_files(ModelFolder(Path(setup.folder)).reward_file)
            if status != "applied":  # recorded in the training's log
                print(f"reward function's files not closed off: {status}", file=sys.stderr)
            reward_sandbox.limit_memory(memory_mb, learner_mb=ACTING_MB if actor else 0)
            connection.send(("ready", None))
        except BaseException as error:
            _send_error(connection, error)
            return
        _serve(connection, batch, recorder, actor, frames)
    finally:
        reward_sandbox.end_descendants()


def _serve(
    connection: Connection,
    batch: BatchedDeepRacer,
    recorder: StepRecorder | None,
    actor: PolicyActor | None,
    frames: SharedFrames | None,
) -> None:
    """Answer the trainer: "reset"; "step" with the cars' actions; and where the part
    acts, "act" with the policy's weights (acting on the cars' current observations) and
    "step_act" (a step, then acting on its observations)."""
    latest: Any = None  # the cars' current observations
    while True:
        try:
            kind, value = connection.recv()
        except (EOFError, OSError):
            return  # the trainer is gone
        if kind == "close":
            return
        try:
            reply: Any
            if kind == "reset":
                reply = latest = batch.reset()
            elif kind == "act":
                assert actor and frames and latest is not None, "the part acts after a reset"
                actor.load(value)
                reply = frames.put(actor.act(latest))
            else:
                step = PartStep.of(batch, batch.step(value), recorder)
                latest = step.obs
                if kind == "step_act":
                    assert actor and frames, "the part was set up without acting"
                    step = step.acted_on(actor, frames)
                reply = step
            connection.send(("ok", reply))
        except BaseException as error:
            _send_error(connection, error)
            return


def _build_part(
    connection: Connection, setup: PartSetup
) -> tuple[BatchedDeepRacer, StepRecorder | None]:

    folder = ModelFolder(Path(setup.folder))
    if setup.reward_seconds is not None:
        # From the watchdog thread while the main thread is stuck in racer code: said as
        # the trainer's own process says it (sim.reward.sandbox.install_call_limit).
        reward_sandbox.install_call_limit(
            setup.reward_seconds,
            folder.reward_file,
            lambda error: _send_error(connection, error),
        )
    # What the reward imports is imported first: its load and first call are timed.
    reward_sandbox.preimport(folder.reward_source())
    config = with_opponents(training_env_config(folder), setup.opponents)
    part = setup.part
    batch = BatchedDeepRacer(
        config, part.cars, setup.seed, first_car=part.first_car, fleet_cars=setup.fleet_cars
    )
    recorder = None
    if setup.record:
        recorder = StepRecorder(part.cars, discrete=setup.discrete, first_car=part.first_car)
        batch.watcher = recorder
    return batch, recorder


def _actor(setup: PartSetup, batch: BatchedDeepRacer) -> PolicyActor:
    from sim.training.actor import PolicyActor  # noqa: PLC0415 (torch: only where the part acts)

    assert setup.acting is not None
    return PolicyActor.copy_for(
        setup.acting, batch.observation_space, batch.action_space, setup.part.cars, setup.seed
    )


def _send_error(connection: Connection, error: BaseException) -> None:
    """Send the error itself when it pickles, else its words; the trainer raises it. Its
    traceback goes to stderr (the training's log), where only a fault of racer-tui's needs
    it."""
    traceback.print_exception(error)
    try:
        pickle.loads(pickle.dumps(error))
        sent: BaseException = error
    except Exception:
        sent = PartError(f"{type(error).__name__}: {error}")
    with contextlib.suppress(BrokenPipeError, ConnectionResetError, OSError):
        connection.send(("error", sent))

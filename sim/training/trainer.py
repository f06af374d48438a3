"""One training run of a garage model: the loop the worker process drives.

Each iteration gathers experience (`RacerPPO.collect`), makes one PPO update, and reports:
an `update` event, `episode` events for the reported car, and now and then an evaluation
(which keeps the best policy in `policy.safetensors`), a checkpoint and a `system` event.
The `Logbook` writes DeepRacer's TrainingMetrics and sim-trace of every car as the cars
step. Files are written atomically or appended in an order that keeps the folder
consistent at every instant: a SIGKILL loses at most the work since the last checkpoint,
and the next run resumes from `checkpoints/`.

Where a run starts: the latest checkpoint if there is one; else the model's
`policy.safetensors` (a clone of a trained model) with a fresh optimizer; else scratch.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import psutil
import torch

from sim.foundation.atomic import write_text_atomic
from sim.garage.folder import BF16_CONVOLUTIONS, ModelError, ModelFolder
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.physics.simulation import reversed_track
from sim.reward import limit as reward_limit
from sim.reward import sandbox as reward_sandbox
from sim.sensors.observations import SensorOptions
from sim.tracks.track import Track
from sim.training import events
from sim.training.actor import ActorSetup
from sim.training.algorithms import check_trainable
from sim.training.checkpoint import BEST, LATEST, Progress, load_checkpoint, save_checkpoint
from sim.training.config import training_env_config
from sim.training.errors import describe_failure, failure_remedy
from sim.training.evaluation import EvaluationReport, run_trials
from sim.training.fleet_parts import PartError, usable_cores
from sim.training.logbook import Logbook
from sim.training.opponents import with_opponents
from sim.training.policy import fill_network, network_spec, open_tensors, policy_data, save_policy
from sim.training.policy_driver import PolicyDriver
from sim.training.ppo import PPOSettings, Rollout, make_ppo, training_numerics
from sim.training.run_history import RunHistory
from sim.training.shards import ShardedVecEnv
from sim.training.vec_env import BatchedVecEnv, FleetVecEnv

REPORTED_CAR = 0  # the car whose episodes are streamed and logged, as DeepRacer's one car
EVALUATION_TRIALS = 5
EVALUATION_SECONDS = 60.0  # an evaluation trial still running after this is "Time Up"
SYSTEM_SECONDS = 2.0


@dataclass(frozen=True)
class RunOptions:
    """How a run is driven; the defaults are what `racer-tui train` uses."""

    minutes: float | None = None  # None: training_params.yaml's MAX_MINUTES
    cars: int | None = None  # per process; None: by sensor (see `default_cars`)
    # Processes that step the cars (sim.training.shards), and threads of the PPO update
    # (the training child's default is the cores less one: `default_processes`).
    processes: int = 1
    seed: int | None = None
    checkpoint_seconds: float = 10.0
    evaluation_seconds: float = 5.0  # least time between evaluations
    min_samples: int | None = None
    max_samples: int | None = None
    # The memory the reward function may use in the trainer's own process, beyond the
    # learner's (see `Trainer._contain`); None: no limit (a trainer that runs no racer code).
    reward_memory_mb: int | None = None
    # Other racers' cars on the track with every training car (sim.training.opponents):
    # garage models, bundle files or `reference`; none: the model's own race type.
    opponents: tuple[str, ...] = ()


def default_cars(sensors: tuple[str, ...]) -> int:
    """Cars per process: many for cheap sensors, fewer when every car renders a camera."""
    return 32 if "camera" in sensors else 64


def sample_limits(sensors: tuple[str, ...], cars: int) -> tuple[int, int]:
    """(least, most) samples per update around the episode-count rule; camera frames are
    large, so camera rollouts are capped lower to keep memory small."""
    most = 4096 if "camera" in sensors else 16384
    return min(2048, most), max(most, cars * 2)


# What an update needs beyond its rollout (torch's working memory, the network's
# gradients and optimizer state): the margin of the trainer's memory limit.
LEARNER_BASE_MB = 1024


class Trainer:
    """Trains one model folder until the time limit or `should_stop()`."""

    def emit(self, event: events.Event) -> None:
        self._emit_out(event)
        self._history.record(event)

    def __init__(
        self,
        folder: ModelFolder,
        emit: Callable[[events.Event], None],
        should_stop: Callable[[], bool],
        options: RunOptions | None = None,
    ) -> None:
        self.folder = folder
        self._emit_out = emit
        # Updates and system readings also go to the model's history, so its charts show
        # every run (sim.training.run_history).
        self._history = RunHistory(folder.training_history)
        self.should_stop = should_stop
        self.options = options or RunOptions()
        self.metadata = folder.metadata()
        problem = folder.car_archive_problem("train")
        if problem is not None:
            raise ModelError(problem)
        check_trainable(self.metadata)  # a sac model is refused, never trained as PPO
        # The network it trains, and the numerics this machine trains it in (recorded in
        # every state written, as the physics is).
        self.spec = network_spec(self.metadata, SensorOptions())
        self.numerics = training_numerics(self.spec)
        self.hyperparameters = folder.hyperparameters()
        params = folder.training_params()
        minutes = self.options.minutes if self.options.minutes is not None else params.max_minutes
        if not (math.isfinite(minutes) and minutes > 0):
            raise ModelError(f"the training time must be more than 0 minutes, not {minutes:g}.")
        self.limit_seconds = minutes * 60.0
        self.minutes = minutes
        try:
            self.settings = PPOSettings.from_hyperparameters(self.hyperparameters)
        except ValueError as error:
            raise ModelError(f"{folder.hyperparameters_file}: {error}") from None
        self.config = with_opponents(training_env_config(folder), self.options.opponents)
        self.processes = self.options.processes
        if self.processes < 1:
            raise ModelError(f"a training needs at least 1 process, not {self.processes}.")
        # Each process steps a fleet's worth of cars: a part steps little faster with fewer
        # cars (its step costs little more for many), so more cores drive more cars.
        self.cars = (self.options.cars or default_cars(self.metadata.sensors)) * self.processes
        least, most = sample_limits(self.metadata.sensors, self.cars)
        self.min_samples = self.options.min_samples or least
        self.max_samples = self.options.max_samples or most
        self.progress = Progress()
        self.started_at = datetime.now(UTC)
        self._clock0 = time.monotonic()
        self._processes = [psutil.Process()]  # and the simulation processes, once started
        self._evaluations = 0  # evaluations run: shuffled boxes are drawn from it
        self._processes[0].cpu_percent(interval=None)  # the first reading sets the baseline
        self._last_metrics_write = -math.inf
        self._metrics_write_cost = 0.0

    # --- the run ---------------------------------------------------------------------------
    def run(self) -> events.Ended:
        """Train; always ends with a checkpoint, a policy file and the training state."""
        try:
            resumed_from = self._setup()
        except Exception as error:  # a simulation process's own error too
            if hasattr(self, "env"):
                self.env.close()
            message = describe_failure(error)
            self._write_state("failed", message, error)
            return self._ended("failed", message, error)
        self._clock0 = time.monotonic()  # the time limit counts training, not start-up
        self._contain()
        self._write_state("running", "training")
        self.emit(
            events.Started(
                elapsed=0.0,
                model=self.folder.name,
                track=self.config.track.name,
                sensors=self.metadata.sensors,
                cars=self.cars,
                resumed_from=resumed_from,
                total_steps=self.progress.total_steps,
                max_minutes=self.minutes,
                pid=os.getpid(),
                processes=self.processes,
                opponents=tuple(Path(car).name for car in self.options.opponents),
            )
        )
        kind, message = "finished", "the time limit was reached"
        failure: Exception | None = None
        try:
            try:
                self._loop()
                if self.should_stop():
                    kind, message = "stopped", "training was stopped"
            except Exception as error:
                kind, message, failure = "failed", describe_failure(error), error
            try:
                self._finish()
            except Exception as error:  # the folder stays consistent; say what went wrong
                kind, message, failure = "failed", describe_failure(error), error
        finally:
            self.env.close()  # the simulation processes end with the run, however it ends
        self._write_state(kind, message, failure)
        return self._ended(kind, message, failure)

    def _setup(self) -> str:
        self._remove_leftovers()
        self.logbook = Logbook(
            self.folder.path,
            cars=self.cars,
            episodes_per_iteration=self.settings.episodes_per_update,
            track_length=self.config.track.length,
            waypoints=self.training_track.center,
            discrete=self.metadata.action_space.kind == "discrete",
        )
        self.env = self._fleet()
        env = self.env
        self.model = make_ppo(
            env,
            self.spec,
            self.settings,
            max_samples=self.max_samples,
            seed=self.options.seed,
            # Never more threads than cores: more would only take turns.
            update_threads=min(self.processes, usable_cores()),
        )
        self.network = self.model.network
        resumed_from = self._restore()
        # The metrics may be ahead of the last checkpoint: they number the episodes.
        self.progress = replace(
            self.progress, episodes=max(self.progress.episodes, self.logbook.episodes)
        )
        self._run_elapsed0 = self.progress.elapsed_seconds
        self._first_iteration = self.progress.iteration
        return resumed_from

    def _contain(self) -> None:
        """The trainer's own process steps its part of the fleet, so it runs the racer's
        reward function too: from here on it may grow by the reward's memory and what the
        learner's rollouts and updates need, and (Landlock) read only Python's files, the
        model's folder and its simulation processes' figures, and write only the folder."""
        megabytes = self.options.reward_memory_mb
        if megabytes is None:
            return
        reward_sandbox.limit_memory(megabytes, learner_mb=self._learner_mb())
        figures = [Path(f"/proc/{process.pid}") for process in self._processes[1:]]
        # Signals stay allowed: the trainer ends its simulation processes.
        status = reward_sandbox.close_off_files(
            self.folder.reward_file, [self.folder.path], reads=figures, scope_signals=False
        )
        if status != "applied":  # recorded in the training's log, where its faults go
            print(f"reward function's files not closed off: {status}", file=sys.stderr)

    def _learner_mb(self) -> int:
        """Room for the learner beyond the reward's: its rollout of float32 observations,
        a few copies of it in an update, and the update's working memory."""
        space = self.env.observation_space
        shapes = [sub.shape for sub in getattr(space, "spaces", {}).values()] or [space.shape]
        values = sum(int(np.prod(shape or (1,))) for shape in shapes)
        copies = 4
        return LEARNER_BASE_MB + (self.max_samples * values * 4 * copies) // (1024 * 1024)

    def _fleet(self) -> FleetVecEnv:
        """The cars, in this process or spread over several (the log sees every step)."""
        if self.processes == 1:
            env = BatchedVecEnv(self.config, self.cars, seed=self.options.seed)
            env.batch.watcher = self.logbook
            return env
        limit = reward_limit.active()
        sharded = ShardedVecEnv(
            self.config,
            self.folder.path,
            self.cars,
            self.processes,
            seed=self.options.seed,
            on_step=self.logbook.add_step,
            reward_seconds=limit.seconds if limit is not None else None,
            opponents=self.options.opponents,
            acting=self._part_acting(),
        )
        try:
            for pid in sharded.pids:
                process = psutil.Process(pid)
                process.cpu_percent(interval=None)
                self._processes.append(process)
        except psutil.Error:  # a part ended already: say so as a part's end
            sharded.close()
            raise PartError(
                "a simulation process of this training ended as it started; start the "
                "training again, with --processes 1 if it keeps happening"
            ) from None
        return sharded

    def _part_acting(self) -> ActorSetup | None:
        """How the simulation processes act for their cars: a camera network's forward
        passes are about half of its collection, so each process runs its own cars'; a
        network without one is small, the trainer runs it for every car, and the
        simulation processes need no torch."""
        if not self.spec.conv:
            return None
        return ActorSetup(self.spec, training_numerics(self.spec) == BF16_CONVOLUTIONS)

    def _ended(self, kind: str, message: str, failure: BaseException | None = None) -> events.Ended:
        problem, fix = failure_remedy(failure) if failure is not None else ("", None)
        return events.Ended(
            elapsed=self.elapsed,
            kind=kind,
            message=message,
            total_steps=self.progress.total_steps,
            episodes=self.progress.episodes,
            best_progress=max(self.progress.best_progress, 0.0),
            best_lap=self.progress.best_lap,
            problem=problem,
            fix=fix.name if fix is not None else "",
        )

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self._clock0

    def _loop(self) -> None:
        model = self.model
        model.start_rollouts()
        last_checkpoint = self.elapsed
        last_system = -math.inf
        self._last_evaluation = -math.inf
        self._evaluation_cost = 0.0
        while self.elapsed < self.limit_seconds:
            if self.should_stop():
                return
            started = time.monotonic()
            # Sim-trace rows come from the logbook, which sees every car's steps.
            rollout = model.collect(
                self.settings.episodes_per_update, self.min_samples, self.max_samples
            )
            if self.should_stop():
                return  # a stop during collection: do not spend time on an update
            model.train()
            seconds = time.monotonic() - started
            self.progress = replace(
                self.progress,
                iteration=self.progress.iteration + 1,
                total_steps=self.progress.total_steps + rollout.steps,
                elapsed_seconds=self._run_elapsed0 + self.elapsed,
            )
            self._report_iteration(rollout, seconds)
            if self._evaluation_due():
                self._evaluate()
            self._write_metrics()
            if self.elapsed - last_checkpoint >= self.options.checkpoint_seconds:
                self._checkpoint()
                last_checkpoint = self.elapsed
            if self.elapsed - last_system >= SYSTEM_SECONDS:
                self._system()
                last_system = self.elapsed
            self._write_state("running", "training")

    def _remove_leftovers(self) -> None:
        """Temporary files of a run killed mid-write (the real files are intact)."""
        places = (
            self.folder.path,
            self.folder.checkpoints_dir,
            self.folder.training_metrics_file.parent,
        )
        for place in places:
            for leftover in place.glob(".*.tmp"):
                if leftover.is_file() and not leftover.is_symlink():
                    leftover.unlink(missing_ok=True)

    # --- where the weights come from ---------------------------------------------------------
    def _restore(self) -> str:
        latest = self.folder.checkpoints_dir / LATEST
        if latest.is_file():
            self.progress = load_checkpoint(latest, self.network, self.model.policy.optimizer)
            return "checkpoint"
        if self.folder.has_policy():
            data, where = policy_data(self.folder.policy_file)
            facts, tensors = open_tensors(data, where)
            fill_network(self.network, facts, tensors, where)
            return "policy"
        return "scratch"

    # --- reporting -----------------------------------------------------------------------------
    def _report_iteration(self, rollout: Rollout, seconds: float) -> None:
        # The logbook numbered the episodes as they finished, as the metrics have them.
        for episode in self.logbook.take_finished():
            if episode.car != REPORTED_CAR:
                continue
            self.emit(
                events.Episode(
                    elapsed=self.elapsed,
                    episode=episode.number,
                    car=episode.car,
                    reward=episode.reward,
                    progress=episode.progress,
                    lap_time=episode.lap_time,
                    status=episode.status,
                    steps=episode.steps,
                )
            )
        self.progress = replace(self.progress, episodes=self.logbook.episodes)
        laps = [e.lap_time for e in rollout.episodes if e.lap_time is not None]
        stats = self.model.last_update
        self.emit(
            events.Update(
                elapsed=self.elapsed,
                iteration=self.progress.iteration,
                total_steps=self.progress.total_steps,
                episodes=self.progress.episodes,
                entropy=stats.entropy,
                policy_loss=stats.policy_loss,
                value_loss=stats.value_loss,
                approx_kl=stats.approx_kl,
                clip_fraction=stats.clip_fraction,
                steps_per_second=rollout.steps / max(seconds, 1e-9),
                iteration_episodes=len(rollout.episodes),
                mean_reward=_mean([e.reward for e in rollout.episodes]),
                mean_progress=_mean([e.progress for e in rollout.episodes]),
                laps=len(laps),
                best_lap=min(laps) if laps else None,
            )
        )

    def _system(self) -> None:
        """CPU (100 % a core, as `top` counts) and memory of the trainer and its simulation
        processes together."""
        cpu = rss = 0.0
        for process in self._processes:
            try:
                with process.oneshot():
                    cpu += process.cpu_percent(interval=None)
                    rss += process.memory_info().rss / 1e6
            except psutil.Error:  # a simulation process just ended: the run is ending too
                continue
        self.emit(events.System(elapsed=self.elapsed, cpu_percent=cpu, rss_mb=round(rss, 1)))

    # --- evaluation and the best policy ---------------------------------------------------------
    def _evaluation_due(self) -> bool:
        since = self.elapsed - self._last_evaluation
        # At most ~10% of the time goes to evaluation, and never more often than asked.
        return since >= max(self.options.evaluation_seconds, 9.0 * self._evaluation_cost)

    def evaluate_now(self) -> EvaluationReport:
        # The weights of the moment, driven as races drive them (numpy: a camera model's
        # evaluation takes about a third of torch's time).
        driver = PolicyDriver(self.network, self.metadata, name=self.folder.name, content_hash="")
        race = self.config.race
        # Shuffled boxes are drawn again for every evaluation, as DeepRacer draws them for
        # every episode: one fixed draw can hold a pair that no car passes (two boxes half a
        # metre apart in opposite lanes), and would cap every evaluation below a full set.
        self._evaluations += 1
        shuffled = race is not None and race.obstacles.randomize
        results = run_trials(
            driver,
            self.evaluation_track,
            EVALUATION_TRIALS,
            max_seconds=EVALUATION_SECONDS,
            race=race,  # a model meets its boxes or bots
            seed=self._evaluations if shuffled else 0,
        )
        return EvaluationReport(track=self.config.track.name, trials=tuple(results))

    @property
    def training_track(self) -> Track:
        """The track as this model trains on it: reversed with REVERSE_DIR (its waypoints
        are the sim-trace's)."""
        track = self.config.track
        return reversed_track(track) if self.config.is_reversed else track

    @property
    def evaluation_track(self) -> Track:
        """DeepRacer's evaluation episodes during training run on the training's lines."""
        return self.training_track

    def _evaluate(self) -> None:
        started = time.monotonic()
        self.model.policy.set_training_mode(False)
        report = self.evaluate_now()
        self._evaluation_cost = time.monotonic() - started
        self._last_evaluation = self.elapsed
        better = self._is_better(report)
        if better:
            self.progress = replace(
                self.progress,
                best_progress=report.mean_progress,
                best_lap=report.mean_lap if report.laps == len(report.trials) else None,
            )
            # The best policy is what races use; its checkpoint lets a racer go back to it.
            save_policy(self.folder.policy_file, self.network)
            save_checkpoint(
                self.folder.checkpoints_dir / BEST,
                self.network,
                self.model.policy.optimizer,
                self.progress,
            )
        self.logbook.add_evaluation([(t.seconds, t.progress, t.status) for t in report.trials])
        laps = [t.lap_time for t in report.trials if t.lap_time is not None]
        self.emit(
            events.Evaluation(
                elapsed=self.elapsed,
                iteration=self.progress.iteration,
                total_steps=self.progress.total_steps,
                trials=len(report.trials),
                laps=report.laps,
                mean_progress=report.mean_progress,
                best_lap=report.best_lap,
                lap_times=tuple(laps),
                statuses=tuple(t.status for t in report.trials),
                best=better,
            )
        )

    def _is_better(self, report: EvaluationReport) -> bool:
        """More mean progress wins (DeepRacer's best-model metric); with every trial a
        lap, a faster mean lap wins."""
        best = self.progress.best_progress
        if report.mean_progress > best + 1e-9:
            return True
        complete = report.laps == len(report.trials)
        if complete and best >= 100.0 - 1e-9:
            lap = report.mean_lap
            return lap is not None and (
                self.progress.best_lap is None or lap < self.progress.best_lap
            )
        return False

    # --- files -----------------------------------------------------------------------------------
    def _write_metrics(self, force: bool = False) -> None:
        # Appending copies the metrics file, which grows with the log: keep it to a small
        # share of the time.
        if not force and self.elapsed - self._last_metrics_write < 20 * self._metrics_write_cost:
            return
        started = time.monotonic()
        self.logbook.flush()
        self._metrics_write_cost = time.monotonic() - started
        self._last_metrics_write = self.elapsed

    def _checkpoint(self) -> None:
        self.progress = replace(self.progress, elapsed_seconds=self._run_elapsed0 + self.elapsed)
        path = self.folder.checkpoints_dir / LATEST
        save_checkpoint(path, self.network, self.model.policy.optimizer, self.progress)
        self.emit(
            events.Checkpoint(
                elapsed=self.elapsed,
                iteration=self.progress.iteration,
                total_steps=self.progress.total_steps,
                file=str(path.relative_to(self.folder.path)),
            )
        )

    def _finish(self) -> None:
        if self.progress.iteration == self._first_iteration:
            return  # stopped before any update: nothing new to keep, the old files stand
        if self.progress.best_progress < 0:
            self._evaluate()  # a run too short for an evaluation still leaves a policy
        self._write_metrics(force=True)
        self._checkpoint()

    def _write_state(self, state: str, message: str, failure: BaseException | None = None) -> None:
        problem, fix = failure_remedy(failure) if failure is not None else ("", None)
        document: dict[str, Any] = {
            "state": state,
            "pid": os.getpid(),
            "started_at": self.started_at.isoformat(),
            "updated_at": datetime.now(UTC).isoformat(),
            "elapsed_seconds": round(self.progress.elapsed_seconds, 3),
            "steps": self.progress.total_steps,
            "episodes": self.progress.episodes,
            "best_progress": max(self.progress.best_progress, 0.0),
            "best_lap": self.progress.best_lap,
            "message": message,
            # A failure's remedy apart, for a front end that offers it its own way.
            "problem": problem,
            "fix": fix.name if fix is not None else "",
            # The car the policy learnt to drive: the Garage says when today's differs.
            "physics": CURRENT_PHYSICS,
            "numerics": self.numerics,  # sim.training.ppo.training_numerics
            "budget_minutes": self.minutes,  # offered again for the next run
        }
        write_text_atomic(self.folder.training_state_file, json.dumps(document, indent=2) + "\n")


def _mean(values: list[float]) -> float:
    return float(np.mean(values)) if values else 0.0


def train_folder(
    folder: ModelFolder,
    emit: Callable[[events.Event], None],
    should_stop: Callable[[], bool] = lambda: False,
    options: RunOptions | None = None,
) -> events.Ended:
    """Run one training of `folder` in this process (the worker and tests use this)."""
    torch.set_num_threads(1)
    trainer = Trainer(folder, emit, should_stop, options)
    ended = trainer.run()
    emit(ended)
    return ended

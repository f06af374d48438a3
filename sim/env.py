"""The DeepRacer gymnasium environment, single and batched.

Configuration is what a DeepRacer model is made of: a track, an action space in
`model_metadata.json` form, a sensor list and a reward function. Episodes follow
DeepRacer training: off-track, reversed, immobilized and crashed end an episode, a lap
completes it, and starts move round the track from one episode to the next (or not, with
CHANGE_START_POSITION off). The first step of each episode is DeepRacer's "prepare" step:
reward 0, the function is not called.

Every car has a reward module of its own: in DeepRacer one simulation worker drives one car,
so a reward function's module-level state belongs to one car (see `RewardFunction.fresh`).

`DeepRacerEnv` is the standard single-car env (registered as `RacerTui/DeepRacer-v0`);
`BatchedDeepRacer` steps many cars in one process with automatic resets, which is how
training keeps two CPU cores busy.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from sim.deepracer.action_space import FULL_RANGE_CONTINUOUS, ActionSpace, parse_action_space
from sim.deepracer.vocabulary import EpisodeStatus, normalise_sensors
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.physics.objects.field import ObjectField
from sim.physics.objects.settings import RaceSettings
from sim.physics.simulation import EpisodeRules, TrackSimulation
from sim.reward.function import load_reward_function, load_reward_source
from sim.reward.template_files import shipped_template
from sim.sensors.observations import Observer, SensorOptions
from sim.sensors.randomisation.perturbation import draw_perturbation
from sim.sensors.randomisation.settings import CameraRandomisation
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

DEFAULT_TEMPLATE = "follow_center_line"  # DeepRacer's default reward function

ENV_ID = "RacerTui/DeepRacer-v0"
RewardCallable = Callable[[Mapping[str, Any]], float]


@dataclass(frozen=True)
class EnvConfig:
    """Everything that defines a training or evaluation environment."""

    track: Track
    action_space: ActionSpace = FULL_RANGE_CONTINUOUS
    sensors: tuple[str, ...] = ("vector",)
    reward: RewardCallable | None = None  # None: DeepRacer's follow-the-centre-line sample
    rules: EpisodeRules = field(default_factory=EpisodeRules)
    sensor_options: SensorOptions = field(default_factory=SensorOptions)
    car: CarSpec = DEEPRACER_CAR
    is_reversed: bool = False  # DeepRacer's REVERSE_DIR: drive the track the other way round
    race: RaceSettings | None = None  # boxes or bot cars: None for a time trial
    # A camera model's training draws each car a camera every episode (sim.sensors.randomisation);
    # off (the plain render) unless the model asks for it. Only camera models see it.
    camera_randomisation: CameraRandomisation = CameraRandomisation.OFF
    # Objects a higher floor puts on the track with the cars instead of `race`'s: a
    # training's opponents, driven by their own models (sim.race.opponents). Given the
    # cars' simulation, it returns their field.
    objects_for: Callable[[TrackSimulation], ObjectField] | None = None

    @classmethod
    def build(
        cls,
        track: Track | str,
        action_space: object = None,
        sensors: object = ("vector",),
        reward: RewardCallable | str | None = None,
        **kwargs: Any,
    ) -> EnvConfig:
        """Accept the loose forms people write: names, metadata dicts, file paths."""
        if isinstance(track, str):
            track = resolve_track(track)
        if action_space is None:
            space = FULL_RANGE_CONTINUOUS
        elif isinstance(action_space, ActionSpace):
            space = action_space
        else:
            space = parse_action_space(action_space)
        if isinstance(reward, str):
            reward = load_reward_function(reward)
        return cls(
            track=track,
            action_space=space,
            sensors=normalise_sensors(sensors),  # type: ignore[arg-type]
            reward=reward,
            **kwargs,
        )

    def reward_function(self) -> RewardCallable:
        if self.reward is not None:
            return self.reward
        return load_reward_source(shipped_template(DEFAULT_TEMPLATE), DEFAULT_TEMPLATE)

    def reward_functions(self, n_cars: int) -> list[RewardCallable]:
        """One reward function per car, each in a module of its own when it was loaded from
        a file (a plain callable given in code is shared: it is the caller's to make)."""
        function = self.reward_function()
        fresh = getattr(function, "fresh", None)
        if not callable(fresh):
            return [function] * n_cars
        # Fresh copies for every car, so that the config's own module is never stepped and
        # two envs built from one config never share a car's state either.
        return [fresh() for _ in range(n_cars)]

    def simulation(
        self, n_cars: int, first_car: int = 0, fleet_cars: int | None = None
    ) -> TrackSimulation:
        """The cars' simulation, on the track driven the way this config drives it.
        `first_car`, `fleet_cars`: these are cars `first_car`.. of a larger training fleet
        (sim.training.shards); their objects are drawn from `first_car`, so that each part
        of the fleet meets boxes and bots of its own."""
        sim = TrackSimulation(
            self.track,
            n_cars,
            car=self.car,
            rules=self.rules,
            is_reversed=self.is_reversed,
            race=self.race,
            seed=first_car,
            first_car=first_car,
            fleet_cars=fleet_cars,
        )
        if self.objects_for is not None:
            sim.objects = self.objects_for(sim)
        return sim


class StepWatcher(Protocol):
    """Sees every step of a batch: the simulation just before it and just after it."""

    def before_step(self, sim: TrackSimulation) -> None: ...

    def after_step(
        self, sim: TrackSimulation, actions: np.ndarray, rewards: np.ndarray
    ) -> None: ...


@dataclass
class StepInfo:
    """Per-car outcome of one batched step."""

    status: EpisodeStatus
    progress: float
    steps: int


class BatchedDeepRacer:
    """N cars, one process: step them together, reset finished ones automatically.

    `step` returns observations of the *next* episode for cars that just finished, and
    puts the final observation in `final_observations` (the convention of SB3's VecEnv).
    """

    def __init__(
        self,
        config: EnvConfig,
        n_cars: int,
        seed: int | None = None,
        *,
        first_car: int = 0,
        fleet_cars: int | None = None,
    ) -> None:
        self.config = config
        self.n = n_cars
        self.sim = config.simulation(n_cars, first_car, fleet_cars)
        self.observer = Observer(self.sim, config.sensors, config.sensor_options)
        # Camera randomisation: a camera drawn per car per episode from `seed` (None: fresh).
        self._camera_draws = np.random.default_rng(seed) if randomises_camera(config) else None
        self.observation_space = self.observer.space
        self.action_space = config.action_space.gym_space()
        self._rewards_by_car = config.reward_functions(n_cars)
        self.final_observations: list[Any] = [None] * n_cars
        # Told of every step before it is taken and after it, before finished cars restart,
        # so a training log sees each step as it happened (sim.training.logbook).
        self.watcher: StepWatcher | None = None

    def reset(self) -> Any:
        self.sim.reset_all()
        self._draw_cameras(range(self.n))
        return self.observer.observe()

    def _draw_cameras(self, cars: Sequence[int]) -> None:
        """New episodes' cameras for `cars` when the config randomises the camera."""
        draws = self._camera_draws
        if draws is None:
            return
        draw_cameras(self.observer, self.config.camera_randomisation, draws, cars)

    def step(
        self, actions: np.ndarray
    ) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, list[StepInfo]]:
        sim = self.sim
        steering, speed = self.config.action_space.targets(actions)
        watcher = self.watcher
        if watcher is not None:
            watcher.before_step(sim)
        sim.apply(steering, speed)
        rewards = self._rewards()
        if watcher is not None:
            watcher.after_step(sim, actions, rewards)
        status = sim.status.copy()
        progress = sim.progress
        infos = [
            StepInfo(status=status[i], progress=float(progress[i]), steps=int(sim.steps[i]))
            for i in range(self.n)
        ]
        truncated = sim.timed_out
        terminated = sim.done & ~truncated
        finished = np.flatnonzero(terminated | truncated)
        obs = self.observer.observe()
        if len(finished):
            finished_cars: list[int] = finished.tolist()
            for car in finished_cars:
                self.final_observations[car] = _row(obs, car)
            sim.reset_cars(finished_cars)
            self._draw_cameras(finished_cars)
            # Only the restarted cars moved: observing just them saves a whole-fleet
            # camera render or lidar scan on most training steps.
            _set_rows(obs, finished, self.observer.observe(finished_cars))
        return obs, rewards, terminated, truncated, infos

    def _rewards(self) -> np.ndarray:
        rewards = np.zeros(self.n, dtype=np.float64)
        functions = self._rewards_by_car
        steps = self.sim.steps
        for i, params in enumerate(self.sim.all_params()):
            if steps[i] > 1:  # step 1 is DeepRacer's "prepare" step
                rewards[i] = functions[i](params)
        return rewards


def randomises_camera(config: EnvConfig) -> bool:
    """Whether episodes of `config` draw camera perturbations: a camera model whose
    settings turn any family on."""
    return config.camera_randomisation.on and "camera" in config.sensors


def draw_cameras(
    observer: Observer,
    settings: CameraRandomisation,
    rng: np.random.Generator,
    cars: Sequence[int],
) -> None:
    """A new episode's camera for each of `cars`, drawn from `rng`."""
    chosen = [draw_perturbation(settings, rng) for _ in cars]
    noise_seed = int(rng.integers(2**62))  # seeds the sensor noise on the first call only
    observer.perturb_camera(list(cars), chosen, noise_seed=noise_seed)


def _set_rows(obs: Any, cars: np.ndarray, rows: Any) -> None:
    if isinstance(obs, dict):
        for key, part in obs.items():
            part[cars] = rows[key]
    else:
        obs[cars] = rows


def _row(obs: Any, car: int) -> Any:
    if isinstance(obs, dict):
        return {key: value[car].copy() for key, value in obs.items()}
    return obs[car].copy()


class DeepRacerEnv(gym.Env[Any, Any]):
    """A single-car DeepRacer environment following the gymnasium API."""

    metadata = {"render_modes": [], "render_fps": 15}  # noqa: RUF012 - gymnasium's convention

    def __init__(self, config: EnvConfig | None = None, **build_kwargs: Any) -> None:
        super().__init__()
        self.config = config if config is not None else EnvConfig.build(**build_kwargs)
        self.sim = self.config.simulation(1)
        self.observer = Observer(self.sim, self.config.sensors, self.config.sensor_options)
        self.observation_space = self.observer.space
        self.action_space = self.config.action_space.gym_space()
        self._reward = self.config.reward_functions(1)[0]

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start an episode. `options={"start": fraction}` fixes the start (0..1 of a lap).

        Without it the start moves round the track each episode (DeepRacer's round robin);
        a seed makes the first start a seeded random point instead, reproducibly.
        """
        super().reset(seed=seed)
        start_s: float | None = None
        length = self.config.track.length
        if options and "start" in options:
            start_s = (float(options["start"]) % 1.0) * length
        elif seed is not None:
            start_s = float(self.np_random.uniform(0.0, length))
        self.sim.reset_car(0, start_s)
        if randomises_camera(self.config):  # a new camera every episode, from the env's seed
            draw_cameras(self.observer, self.config.camera_randomisation, self.np_random, [0])
        return _row(self.observer.observe(), 0), self._info()

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        steering, speed = self.config.action_space.targets(np.asarray(action)[None, ...])
        self.sim.apply(steering, speed)
        # Step 1 is DeepRacer's "prepare" step: no params built, no function called.
        reward = float(self._reward(self.sim.all_params()[0])) if self.sim.steps[0] > 1 else 0.0
        truncated = bool(self.sim.timed_out[0])
        terminated = bool(self.sim.done[0]) and not truncated
        return _row(self.observer.observe(), 0), reward, terminated, truncated, self._info()

    def _info(self) -> dict[str, Any]:
        sim = self.sim
        return {
            "status": str(sim.status[0]),
            "progress": float(sim.progress[0]),
            "steps": int(sim.steps[0]),
            "x": float(sim.fleet.x[0]),
            "y": float(sim.fleet.y[0]),
            "heading": float(sim.heading_deg[0]),
            "speed": float(sim.fleet.speed[0]),
        }

    def params(self) -> dict[str, Any]:
        """DeepRacer's reward params for the current state."""
        return self.sim.all_params()[0]


def register() -> None:
    """Register `RacerTui/DeepRacer-v0` with gymnasium (idempotent)."""
    if ENV_ID not in gym.registry:
        gym.register(id=ENV_ID, entry_point="sim.env:DeepRacerEnv")


register()

"""A training against opponents (`racer-tui train MODEL --opponent CAR`): every training
car races the named cars, in this process or in simulation processes of its own, and what
cannot be raced is one sentence."""

from __future__ import annotations

from dataclasses import replace

import pytest

from sim.garage.folder import ModelError, ModelFolder
from sim.garage.options import new_model
from sim.race.opponents import OpponentField
from sim.training import events
from sim.training.config import training_env_config
from sim.training.opponents import with_opponents
from sim.training.policy import build_network, save_policy
from sim.training.policy_driver import PolicyDriver
from sim.training.trainer import RunOptions, Trainer
from sim.training.vec_env import BatchedVecEnv

TINY = RunOptions(minutes=5, cars=2, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)


@pytest.fixture
def lidar_model() -> ModelFolder:
    return new_model("lidar", sensors=("vector", "sector_lidar"))


def rival() -> ModelFolder:
    """A garage model with a policy (untrained weights: it drives, badly)."""
    folder = new_model("rival", sensors=("sector_lidar",))
    save_policy(folder.policy_file, build_network(folder.metadata()))
    return folder


def _run(model: ModelFolder, options: RunOptions) -> tuple[Trainer, list[events.Event]]:
    stream: list[events.Event] = []

    def stop() -> bool:
        return sum(isinstance(e, events.Update) for e in stream) >= 2

    trainer = Trainer(model, stream.append, stop, options)
    stream.append(trainer.run())
    return trainer, stream


def test_a_training_races_its_opponents_each_driven_by_its_own_model(
    lidar_model: ModelFolder,
) -> None:
    rival()

    trainer, stream = _run(lidar_model, replace(TINY, opponents=("rival", "reference")))
    started, ended = stream[0], stream[-1]
    assert isinstance(started, events.Started) and started.opponents == ("rival", "reference")
    assert isinstance(ended, events.Ended) and ended.kind == "stopped", ended
    env = trainer.env
    assert isinstance(env, BatchedVecEnv)
    field = env.batch.sim.objects
    assert isinstance(field, OpponentField)
    assert isinstance(field.drivers[0], PolicyDriver) and field.drivers[1].name == "reference"
    assert all(sim.n == 2 for sim in field.sims)  # one car of each per training car
    assert sum(float(sim.travelled.sum()) != 0.0 for sim in field.sims) >= 1
    assert lidar_model.has_policy()


def test_opponents_race_in_every_simulation_process(lidar_model: ModelFolder) -> None:
    rival()  # its policy is loaded in the simulation process too
    options = replace(TINY, processes=2, opponents=("rival",))
    _trainer, stream = _run(lidar_model, options)
    started, ended = stream[0], stream[-1]
    assert isinstance(started, events.Started) and started.processes == 2
    assert started.opponents == ("rival",)
    assert isinstance(ended, events.Ended) and ended.kind == "stopped", ended
    updates = [e for e in stream if isinstance(e, events.Update)]
    assert updates and updates[-1].total_steps > 0


@pytest.mark.parametrize(
    ("sensors", "opponents", "said"),
    [
        (("vector",), ("reference",), "--opponent: a model that races among objects needs"),
        (("sector_lidar",), ("reference",) * 6, "at most 5 opponents"),
        (("sector_lidar",), ("nobody-here",), "--opponent: "),
    ],
)
def test_opponents_a_training_cannot_have_are_one_sentence(
    sensors: tuple[str, ...], opponents: tuple[str, ...], said: str
) -> None:
    folder = new_model("refused", sensors=sensors)
    with pytest.raises(ModelError, match=said) as raised:
        # Refused as the config is made, or where a simulation resolves the cars.
        with_opponents(training_env_config(folder), opponents).simulation(1)
    assert "\n" not in str(raised.value) and "Traceback" not in str(raised.value)


def test_a_car_that_is_not_there_is_refused_before_the_training_starts(
    lidar_model: ModelFolder,
) -> None:
    # The worker says a RemedyError from setting up as the run's failure, in its sentence.
    with pytest.raises(ModelError, match="--opponent: there is no model named 'nobody-here'"):
        Trainer(lidar_model, print, lambda: True, replace(TINY, opponents=("nobody-here",)))
    assert not lidar_model.has_policy()

"""A training's opponents as its config gives them: `racer-tui train MODEL --opponent CAR`
names the cars (a garage model, a `.racer-bundle` file, a car archive imported into the
garage, or `reference`), and every simulation of the training, in whichever process it
runs, puts them on the track with its cars (sim.race.opponents).

Opponents take the place of a head-to-bot model's bot cars for that training; a model
trained without them keeps its race type's objects, bots included. Each process resolves
the cars itself, from their names: a policy is loaded where its cars are driven.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from sim.env import EnvConfig
from sim.garage.folder import ModelError, open_model
from sim.garage.imported import BUNDLE_SUFFIX
from sim.garage.options import blind_to_objects
from sim.physics.objects.settings import RaceType
from sim.physics.simulation import TrackSimulation
from sim.race.driver import REFERENCE_NAME
from sim.race.opponents import MOST_OPPONENTS, OpponentField
from sim.training.drivers import RaceSetupError, resolve_driver


def with_opponents(config: EnvConfig, opponents: Sequence[str]) -> EnvConfig:
    """`config` whose simulations race `opponents` beside every car; `config` itself when
    there are none. A training they cannot join is a ModelError in one sentence."""
    if not opponents:
        return config
    check_opponents(config, opponents)
    cars = tuple(opponents)

    def field(sim: TrackSimulation) -> OpponentField:
        try:
            # The simulation's own track: reversed when the model drives it reversed, so a
            # reference opponent follows the racing line of the way it is driven.
            drivers = [resolve_driver(car, sim.track) for car in cars]
        except RaceSetupError as error:
            raise ModelError(f"--opponent: {error}") from None
        return OpponentField(sim, drivers, seed=sim.first_car)

    return replace(config, race=None, objects_for=field)


def opponent_spec(given: str) -> str:
    """A car as the training child is told it: a bundle by its whole path (the child may
    not share the directory it was typed in), anything else as typed."""
    given = given.strip()
    return str(Path(given).resolve()) if given.endswith(BUNDLE_SUFFIX) else given


def check_opponents(config: EnvConfig, opponents: Sequence[str]) -> None:
    """Refuse, in one sentence, opponents a training cannot have: found before any runs,
    without loading a policy (a policy loads only where it drives)."""
    for car in opponents:
        missing = _missing_car(car)
        if missing is not None:
            raise ModelError(f"--opponent: {missing}")
    if len(opponents) > MOST_OPPONENTS:
        raise ModelError(
            f"--opponent: a training takes at most {MOST_OPPONENTS} opponents (a race's "
            f"grid holds 6 cars), not {len(opponents)}."
        )
    blind = blind_to_objects(RaceType.HEAD_TO_BOT.value, config.sensors)
    if blind is not None:
        raise ModelError(f"--opponent: {blind}")
    if config.race is not None and config.race.race_type is RaceType.OBJECT_AVOIDANCE:
        raise ModelError(
            "--opponent: an object-avoidance model trains among boxes, not cars; train a "
            "time-trial or head-to-bot model against opponents."
        )
    if config.rules.alternate_direction:
        raise ModelError(
            "--opponent: opponents drive the track's way round only; turn "
            "ALTERNATE_DRIVING_DIRECTION off in training_params.yaml to train against them."
        )


def _missing_car(car: str) -> str | None:
    """Why `car` names nothing that can drive, or None."""
    if car == REFERENCE_NAME:
        return None
    if car.endswith(BUNDLE_SUFFIX):
        return None if Path(car).is_file() else f"there is no bundle file {car}."
    try:
        folder = open_model(car)
    except ModelError as error:
        return str(error)
    if folder.has_policy() or folder.drives_with_car_archive():
        return None
    return f"{folder.name} has no trained policy yet; train it first, then race it."

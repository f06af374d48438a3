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

from sim.env import EnvConfig
from sim.garage.folder import ModelError
from sim.garage.options import blind_to_objects
from sim.physics.objects.settings import RaceType
from sim.physics.simulation import TrackSimulation
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


def check_opponents(config: EnvConfig, opponents: Sequence[str]) -> None:
    """Refuse, in one sentence, opponents a training cannot have."""
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

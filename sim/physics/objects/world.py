"""The objects of a race type, for a simulation: boxes, bot cars or none."""

from __future__ import annotations

from sim.physics.objects.bots import BotField
from sim.physics.objects.field import ObjectField, ObstacleField
from sim.physics.objects.settings import RaceSettings, RaceType
from sim.tracks.track import Track


def object_field(
    track: Track, race: RaceSettings | None, cars: int, *, seed: int = 0
) -> ObjectField | None:
    """`race`'s objects for each of `cars` cars (placed from `seed`); None for a time trial."""
    if race is None:
        return None
    if race.race_type is RaceType.OBJECT_AVOIDANCE and race.obstacles.boxes:
        return ObstacleField(track, race.obstacles, cars, seed=seed)
    if race.race_type is RaceType.HEAD_TO_BOT and race.bots.count:
        return BotField(track, race.bots, cars, seed=seed)
    return None

"""A race type's settings, with DeepRacer's own defaults (deepracer-simapp
`obstacles_agent_ctrl.py`, `bot_cars_agent_ctrl.py`); `sim.physics.objects.reading` reads them from
`training_params.yaml`."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Final


class RaceType(StrEnum):
    TIME_TRIAL = "TIME_TRIAL"
    OBJECT_AVOIDANCE = "OBJECT_AVOIDANCE"
    HEAD_TO_BOT = "HEAD_TO_BOT"
    # Racers' models on the track together (simapp evaluates it; nobody trains it).
    HEAD_TO_MODEL = "HEAD_TO_MODEL"

    @property
    def words(self) -> str:
        """As a racer says it: "time trial", "object avoidance", "head-to-bot"."""
        return {
            "TIME_TRIAL": "time trial",
            "OBJECT_AVOIDANCE": "object avoidance",
            "HEAD_TO_BOT": "head-to-bot",
        }.get(self.value, "head-to-head")


class Lane(StrEnum):
    """The two lanes, each midway between the centre line and one border."""

    INNER = "inner"
    OUTER = "outer"


# The box models simapp places (all drawn 0.4 m along the road and 0.3 m across).
OBSTACLE_TYPES: Final = ("box_obstacle", "deepracer_box_obstacle", "amazon_box_obstacle")
MAX_OBSTACLES: Final = 10  # the console offers up to 10 objects
MAX_BOT_CARS: Final = 6  # and up to 6 bot cars
MAX_BOT_SPEED: Final = 4.0  # m/s


@dataclass(frozen=True)
class ObstacleSettings:
    count: int = 0  # NUMBER_OF_OBSTACLES
    # MIN_DISTANCE_BETWEEN_OBSTACLES, a percentage of the track's length (simapp reads it
    # so), between boxes and from the start line.
    min_distance_percent: float = 2.0
    randomize: bool = False  # RANDOMIZE_OBSTACLE_LOCATIONS: drawn again every episode
    # OBJECT_POSITIONS: fixed (progress 0-1, lane) pairs; when given they are the boxes.
    positions: tuple[tuple[float, Lane], ...] = ()
    obstacle_type: str = "box_obstacle"  # OBSTACLE_TYPE
    bot_car: bool = False  # IS_OBSTACLE_BOT_CAR: the obstacles are parked bot cars

    @property
    def boxes(self) -> int:
        return len(self.positions) if self.positions else self.count


@dataclass(frozen=True)
class BotSettings:
    count: int = 0  # NUMBER_OF_BOT_CARS
    min_distance: float = 2.0  # MIN_DISTANCE_BETWEEN_BOT_CARS, metres
    randomize: bool = False  # RANDOMIZE_BOT_CAR_LOCATIONS
    speed: float = 0.2  # BOT_CAR_SPEED, m/s along the centre line
    lane_change: bool = False  # IS_LANE_CHANGE
    lower_lane_change_time: float = 3.0  # LOWER_LANE_CHANGE_TIME, seconds
    upper_lane_change_time: float = 5.0  # UPPER_LANE_CHANGE_TIME
    lane_change_distance: float = 1.0  # LANE_CHANGE_DISTANCE, metres
    penalty_seconds: float = 2.0  # PENALTY_SECONDS: how long bots pause when hit from behind


@dataclass(frozen=True)
class RaceSettings:
    race_type: RaceType = RaceType.TIME_TRIAL
    obstacles: ObstacleSettings = ObstacleSettings()
    bots: BotSettings = BotSettings()


def race_keys(settings: ObstacleSettings | BotSettings) -> dict[str, object]:
    """An object-avoidance or head-to-bot race's settings as `training_params.yaml` keys,
    the way the DeepRacer console and DRfC write them."""
    if isinstance(settings, BotSettings):
        return {
            "NUMBER_OF_BOT_CARS": settings.count,
            "MIN_DISTANCE_BETWEEN_BOT_CARS": settings.min_distance,
            "RANDOMIZE_BOT_CAR_LOCATIONS": settings.randomize,
            "BOT_CAR_SPEED": settings.speed,
            "IS_LANE_CHANGE": settings.lane_change,
            "LOWER_LANE_CHANGE_TIME": settings.lower_lane_change_time,
            "UPPER_LANE_CHANGE_TIME": settings.upper_lane_change_time,
            "LANE_CHANGE_DISTANCE": settings.lane_change_distance,
        }
    obstacles = settings
    keys: dict[str, object] = {
        "NUMBER_OF_OBSTACLES": obstacles.count,
        "MIN_DISTANCE_BETWEEN_OBSTACLES": obstacles.min_distance_percent,
        "RANDOMIZE_OBSTACLE_LOCATIONS": obstacles.randomize,
        "OBSTACLE_TYPE": obstacles.obstacle_type,
        "IS_OBSTACLE_BOT_CAR": obstacles.bot_car,
    }
    if obstacles.positions:
        keys["OBJECT_POSITIONS"] = [
            f"{progress:g},{-1 if lane is Lane.OUTER else 1}"
            for progress, lane in obstacles.positions
        ]
    return keys

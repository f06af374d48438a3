"""A race type's settings read from `training_params.yaml` under DeepRacer's own keys
(`sim.physics.objects.settings` has them and their defaults).

The file is untrusted: every key is checked, and what is wrong is one sentence naming the
key and what it takes. Keys of another race type are kept but do not apply.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from sim.deepracer.files import DeepRacerFileError, TrainingParams, read_flag
from sim.physics.objects.settings import (
    MAX_BOT_CARS,
    MAX_BOT_SPEED,
    MAX_OBSTACLES,
    OBSTACLE_TYPES,
    BotSettings,
    Lane,
    ObstacleSettings,
    RaceSettings,
    RaceType,
)


def race_settings(params: TrainingParams, where: str = "training_params.yaml") -> RaceSettings:
    """The race type of a model's `training_params.yaml` and, for its type, its settings."""
    try:
        race_type = RaceType(params.race_type.strip().upper())
    except ValueError:
        trained = (kind for kind in RaceType if kind is not RaceType.HEAD_TO_MODEL)
        choices = ", ".join(kind.value for kind in trained)
        raise DeepRacerFileError(
            f"{where}: RACE_TYPE must be one of {choices}, not {params.race_type!r}."
        ) from None
    if race_type is RaceType.HEAD_TO_MODEL:
        raise DeepRacerFileError(
            f"{where}: RACE_TYPE HEAD_TO_MODEL is a race between models, which DeepRacer "
            "does not train; train the model as a TIME_TRIAL or HEAD_TO_BOT and race it "
            "head-to-head with `racer-tui --race A B --rules head-to-head`."
        )
    extra = params.extra
    if race_type is RaceType.OBJECT_AVOIDANCE:
        return RaceSettings(race_type, obstacles=_obstacles(extra, where))
    if race_type is RaceType.HEAD_TO_BOT:
        return RaceSettings(race_type, bots=_bots(extra, where))
    return RaceSettings(race_type)


def _obstacles(data: Mapping[str, Any], where: str) -> ObstacleSettings:
    obstacle_type = data.get("OBSTACLE_TYPE", "box_obstacle")
    if obstacle_type not in OBSTACLE_TYPES:
        raise DeepRacerFileError(
            f"{where}: OBSTACLE_TYPE must be one of {', '.join(OBSTACLE_TYPES)}, "
            f"not {obstacle_type!r}."
        )
    positions = _positions(data.get("OBJECT_POSITIONS", []), where)
    count = _whole(data, "NUMBER_OF_OBSTACLES", 0, MAX_OBSTACLES, where)
    if not positions and count == 0:
        raise DeepRacerFileError(
            f"{where}: an OBJECT_AVOIDANCE race needs NUMBER_OF_OBSTACLES from 1 to "
            f"{MAX_OBSTACLES}, or OBJECT_POSITIONS."
        )
    return ObstacleSettings(
        count=count,
        min_distance_percent=_number(
            data, "MIN_DISTANCE_BETWEEN_OBSTACLES", 2.0, 0.0, 50.0, where=where
        ),
        randomize=read_flag(data, "RANDOMIZE_OBSTACLE_LOCATIONS", False, where),
        positions=positions,
        obstacle_type=str(obstacle_type),
        bot_car=read_flag(data, "IS_OBSTACLE_BOT_CAR", False, where),
    )


def _bots(data: Mapping[str, Any], where: str) -> BotSettings:
    count = _whole(data, "NUMBER_OF_BOT_CARS", 0, MAX_BOT_CARS, where)
    if count == 0:
        raise DeepRacerFileError(
            f"{where}: a HEAD_TO_BOT race needs NUMBER_OF_BOT_CARS from 1 to {MAX_BOT_CARS}."
        )
    lower = _number(data, "LOWER_LANE_CHANGE_TIME", 3.0, 0.0, 600.0, where=where)
    upper = _number(data, "UPPER_LANE_CHANGE_TIME", 5.0, 0.0, 600.0, where=where)
    if upper < lower:
        raise DeepRacerFileError(
            f"{where}: UPPER_LANE_CHANGE_TIME ({upper:g} s) must not be below "
            f"LOWER_LANE_CHANGE_TIME ({lower:g} s)."
        )
    return BotSettings(
        count=count,
        min_distance=_number(data, "MIN_DISTANCE_BETWEEN_BOT_CARS", 2.0, 0.0, 100.0, where=where),
        randomize=read_flag(data, "RANDOMIZE_BOT_CAR_LOCATIONS", False, where),
        speed=_number(data, "BOT_CAR_SPEED", 0.2, 0.0, MAX_BOT_SPEED, where=where),
        lane_change=read_flag(data, "IS_LANE_CHANGE", False, where),
        lower_lane_change_time=lower,
        upper_lane_change_time=upper,
        lane_change_distance=_number(data, "LANE_CHANGE_DISTANCE", 1.0, 0.1, 100.0, where=where),
        penalty_seconds=_number(data, "PENALTY_SECONDS", 2.0, 0.0, 60.0, where=where),
    )


def _positions(value: object, where: str) -> tuple[tuple[float, Lane], ...]:
    """OBJECT_POSITIONS: a list of "progress,lane" strings (DeepRacer's form) or pairs;
    lane -1 is the outer lane, 1 the inner (simapp takes any value but -1 as inner)."""
    if value in (None, "", []):
        return ()
    if not isinstance(value, list) or len(value) > MAX_OBSTACLES:
        raise DeepRacerFileError(
            f"{where}: OBJECT_POSITIONS must be a list of up to {MAX_OBSTACLES} "
            '"progress,lane" entries, for example ["0.3,1", "0.6,-1"].'
        )
    positions = []
    for entry in value:
        parts = entry.split(",") if isinstance(entry, str) else entry
        try:
            progress, lane = float(parts[0]), int(float(parts[1]))
            if len(parts) != 2 or not 0.0 <= progress <= 1.0 or lane not in (1, -1):
                raise ValueError
        except (TypeError, ValueError, IndexError):
            raise DeepRacerFileError(
                f'{where}: OBJECT_POSITIONS entry {entry!r} must be "progress,lane" with '
                "progress from 0 to 1 and lane 1 (inner) or -1 (outer)."
            ) from None
        positions.append((progress, Lane.OUTER if lane == -1 else Lane.INNER))
    return tuple(positions)


def _whole(data: Mapping[str, Any], key: str, default: int, high: int, where: str) -> int:
    value = data.get(key, default)
    if isinstance(value, str) and value.strip().lstrip("-").isdigit():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= high:
        raise DeepRacerFileError(f"{where}: {key} must be a whole number from 0 to {high}.")
    return value


def _number(
    data: Mapping[str, Any], key: str, default: float, low: float, high: float, *, where: str
) -> float:
    value = data.get(key, default)
    try:
        number = float(value) if not isinstance(value, bool) else float("nan")
    except (TypeError, ValueError):
        number = float("nan")
    if not low <= number <= high:  # also false for nan
        raise DeepRacerFileError(f"{where}: {key} must be a number from {low:g} to {high:g}.")
    return number

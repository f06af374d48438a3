"""DeepRacer's words, each defined once: episode statuses, the action space's limits, sensor
names, and the label of the physics that timed a lap.

What simapp writes in its metrics and sim-traces and what the console's model metadata
says; the floors above take these names from here.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from enum import StrEnum
from typing import Final

from sim.foundation.remedies import RemedyError


class EpisodeStatus(StrEnum):
    """DeepRacer's episode status labels, as they appear in metrics and sim-trace files."""

    IN_PROGRESS = "In progress"
    LAP_COMPLETE = "Lap complete"
    OFF_TRACK = "Off track"
    CRASHED = "Crashed"
    REVERSED = "Reversed"
    IMMOBILIZED = "Immobilized"
    TIME_UP = "Time Up"


# --- the action space's limits (the car's too: sim.physics.car takes them from here) -----

MAX_STEERING: Final = 30.0  # degrees either way, positive to the left
MIN_SPEED: Final = 0.1  # m/s
MAX_SPEED: Final = 4.0  # m/s


# --- sensors ----------------------------------------------------------------------------

SENSOR_NAMES = ("camera", "lidar", "sector_lidar", "vector")
DEEPRACER_SENSORS = {
    "FRONT_FACING_CAMERA": "camera",
    "STEREO_CAMERAS": "camera",
    "LIDAR": "lidar",
    "SECTOR_LIDAR": "sector_lidar",
}


class SensorError(RemedyError):
    """An unknown or badly combined sensor; the message lists the valid names."""


def normalise_sensors(names: str | Iterable[str]) -> tuple[str, ...]:
    """Our sensor names for DeepRacer's or ours, deduplicated, in a stable order."""
    items = [names] if isinstance(names, str) else list(names)
    if not items:
        raise SensorError("no sensor given; choose camera, lidar, sector_lidar or vector.")
    chosen: set[str] = set()
    for item in items:
        key = DEEPRACER_SENSORS.get(str(item).upper(), str(item).lower())
        if key not in SENSOR_NAMES:
            valid = ", ".join([*SENSOR_NAMES, *DEEPRACER_SENSORS])
            raise SensorError(f"unknown sensor {item!r}; choose from {valid}.")
        chosen.add(key)
    if {"lidar", "sector_lidar"} <= chosen:
        raise SensorError("choose either LIDAR or SECTOR_LIDAR, not both.")
    return tuple(name for name in SENSOR_NAMES if name in chosen)


# --- the reward params' object keys ------------------------------------------------------


def no_objects() -> dict[str, object]:
    """DeepRacer's object keys when a race has no objects (fresh lists every call)."""
    return {
        "closest_objects": [0, 0],
        "objects_location": [],
        "objects_left_of_center": [],
        "objects_speed": [],
        "objects_heading": [],
        "objects_distance": [],
        "objects_distance_from_center": [],
        "object_in_camera": False,
    }


# --- the physics that timed a lap (racer-tui's field in DeepRacer's evaluation files) ----

PHYSICS_LABEL: Final = re.compile(r"racer-tui/[1-9][0-9]{0,5}|deepracer|physical")


def is_physics(value: object) -> bool:
    """`value` is a physics label: racer-tui's versioned physics, DeepRacer's or a real car."""
    return isinstance(value, str) and PHYSICS_LABEL.fullmatch(value) is not None

"""DeepRacer action spaces, read from `model_metadata.json` form.

Discrete: a list of {"steering_angle": deg, "speed": m/s[, "index": i]}.
Continuous: {"steering_angle": {"low", "high"}, "speed": {"low", "high"}}.
Steering is -30..+30 degrees (positive = left), speed 0.1..4 m/s.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import gymnasium as gym
import numpy as np

from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.foundation.arrays import FloatArray
from sim.foundation.remedies import RemedyError


class ActionSpaceError(RemedyError):
    """An action space that DeepRacer would reject; the message says what to change."""


@dataclass(frozen=True)
class Action:
    steering_angle: float
    speed: float


@dataclass(frozen=True)
class ActionSpace:
    """A validated DeepRacer action space."""

    kind: Literal["discrete", "continuous"]
    actions: tuple[Action, ...] = ()
    steering_range: tuple[float, float] = (-MAX_STEERING, MAX_STEERING)
    speed_range: tuple[float, float] = (MIN_SPEED, MAX_SPEED)

    @property
    def max_speed(self) -> float:
        if self.kind == "discrete":
            return max(action.speed for action in self.actions)
        return self.speed_range[1]

    def speeds(self, levels: int = 4) -> tuple[float, ...]:
        """The speeds a car of this space drives, slowest first: a discrete space's own,
        a continuous range at `levels` evenly spaced speeds."""
        if self.kind == "discrete":
            return tuple(sorted({action.speed for action in self.actions}))
        low, high = self.speed_range
        return tuple(sorted({round(float(v), 3) for v in np.linspace(low, high, levels)}))

    def gym_space(self) -> gym.spaces.Space[Any]:
        """Discrete(n), or a Box in [-1, 1]^2 that `targets` scales to the ranges.

        The normalised Box keeps PPO's Gaussian well-conditioned whatever the ranges are.
        """
        if self.kind == "discrete":
            return gym.spaces.Discrete(len(self.actions))
        return gym.spaces.Box(low=-1.0, high=1.0, shape=(2,), dtype=np.float32)

    def targets(self, actions: np.ndarray) -> tuple[FloatArray, FloatArray]:
        """Map a batch of policy actions to (steering degrees, speed m/s) arrays."""
        if self.kind == "discrete":
            table = self._table
            index = np.asarray(actions, dtype=np.intp).reshape(-1)
            return table[index, 0], table[index, 1]
        raw = np.clip(np.asarray(actions, dtype=np.float64).reshape(-1, 2), -1.0, 1.0)
        return _scale(raw[:, 0], self.steering_range), _scale(raw[:, 1], self.speed_range)

    @functools.cached_property
    def _table(self) -> FloatArray:
        # Built once: every step of a race looks its actions up in it.
        table = np.array([[a.steering_angle, a.speed] for a in self.actions], dtype=np.float64)
        table.flags.writeable = False
        return table

    def to_metadata(self) -> list[dict[str, float | int]] | dict[str, dict[str, float]]:
        """The `action_space` value for model_metadata.json."""
        if self.kind == "discrete":
            return [
                {"steering_angle": a.steering_angle, "speed": a.speed, "index": i}
                for i, a in enumerate(self.actions)
            ]
        return {
            "steering_angle": {"low": self.steering_range[0], "high": self.steering_range[1]},
            "speed": {"low": self.speed_range[0], "high": self.speed_range[1]},
        }


def _scale(unit: FloatArray, bounds: tuple[float, float]) -> FloatArray:
    low, high = bounds
    return np.asarray(low + (unit + 1.0) * 0.5 * (high - low), dtype=np.float64)


def parse_action_space(value: object, kind: str | None = None) -> ActionSpace:
    """Read `action_space` (and optionally `action_space_type`) from model metadata."""
    if isinstance(value, Mapping):
        if kind not in (None, "continuous"):
            raise ActionSpaceError(
                "action_space is a range but action_space_type is not 'continuous'."
            )
        return ActionSpace(
            kind="continuous",
            steering_range=_range(value, "steering_angle", -MAX_STEERING, MAX_STEERING),
            speed_range=_range(value, "speed", MIN_SPEED, MAX_SPEED),
        )
    if isinstance(value, Sequence) and not isinstance(value, str):
        if kind not in (None, "discrete"):
            raise ActionSpaceError(
                "action_space is a list but action_space_type is not 'discrete'."
            )
        if not value:
            raise ActionSpaceError("action_space is empty; give at least one action.")
        actions = tuple(_action(item, i) for i, item in enumerate(value))
        return ActionSpace(kind="discrete", actions=actions)
    raise ActionSpaceError(
        "action_space must be a list of {steering_angle, speed} actions or "
        "{steering_angle: {low, high}, speed: {low, high}} ranges."
    )


def _number(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ActionSpaceError(f"{where} must be a number, not {value!r}.")
    number = float(value)
    if not np.isfinite(number):
        raise ActionSpaceError(f"{where} must be a finite number.")
    return number


def _check(value: float, low: float, high: float, where: str, unit: str) -> float:
    if not low - 1e-9 <= value <= high + 1e-9:
        raise ActionSpaceError(
            f"{where} is {value:g} {unit}; it must be between {low:g} and {high:g}."
        )
    return value


def _action(item: object, i: int) -> Action:
    if not isinstance(item, Mapping) or "steering_angle" not in item or "speed" not in item:
        raise ActionSpaceError(f"action {i} must have a steering_angle and a speed.")
    steer = _check(
        _number(item["steering_angle"], f"action {i} steering_angle"),
        -MAX_STEERING,
        MAX_STEERING,
        f"action {i} steering_angle",
        "degrees",
    )
    speed = _check(
        _number(item["speed"], f"action {i} speed"),
        MIN_SPEED,
        MAX_SPEED,
        f"action {i} speed",
        "m/s",
    )
    return Action(steering_angle=steer, speed=speed)


def _range(value: Mapping[str, Any], key: str, low: float, high: float) -> tuple[float, float]:
    bounds = value.get(key)
    if not isinstance(bounds, Mapping) or "low" not in bounds or "high" not in bounds:
        raise ActionSpaceError(f"continuous action_space needs {key}: {{low, high}}.")
    unit = "degrees" if key == "steering_angle" else "m/s"
    lo = _check(_number(bounds["low"], f"{key}.low"), low, high, f"{key}.low", unit)
    hi = _check(_number(bounds["high"], f"{key}.high"), low, high, f"{key}.high", unit)
    if lo >= hi:
        raise ActionSpaceError(f"{key}.low ({lo:g}) must be below {key}.high ({hi:g}).")
    return lo, hi


def discrete_grid(
    max_steering: float = 30.0,
    steering_levels: int = 5,
    max_speed: float = 1.0,
    speed_levels: int = 2,
) -> ActionSpace:
    """The DeepRacer console's action-space builder: steering levels x speed levels."""
    if steering_levels not in (3, 5, 7):
        raise ActionSpaceError(f"steering levels is {steering_levels}; choose 3, 5 or 7.")
    if speed_levels not in (1, 2, 3):
        raise ActionSpaceError(f"speed levels is {speed_levels}; choose 1, 2 or 3.")
    _check(max_steering, 1.0, MAX_STEERING, "maximum steering angle", "degrees")
    _check(max_speed, MIN_SPEED, MAX_SPEED, "maximum speed", "m/s")
    steers = np.linspace(-max_steering, max_steering, steering_levels)
    speeds = [max_speed * (k + 1) / speed_levels for k in range(speed_levels)]
    actions = tuple(
        Action(steering_angle=round(float(s), 4), speed=round(max(v, MIN_SPEED), 4))
        for s in steers
        for v in speeds
    )
    return ActionSpace(kind="discrete", actions=actions)


#: A racing-capable default: the car's full limits, as the league's benchmarks require.
FULL_RANGE_CONTINUOUS = ActionSpace(kind="continuous")

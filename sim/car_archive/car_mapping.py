"""What a physical DeepRacer does with a model: whether it can run it at all, and the servo
and throttle it gives each action.

The car's navigation node (aws-deepracer-navigation-pkg, `deepracer_navigation_node.py`)
drives relative to the action space, not in degrees and metres per second:

- steering: the action's angle divided by the action space's largest one (the largest
  absolute angle of a discrete space, `high` of a continuous one), so the servo turns to
  that share of its calibrated lock;
- throttle: the car's max-speed setting (its slider) times `a s^2 + b s`, clipped to -1..1,
  the parabola through (0, 0), (top/2, 0.8) and (top, 1.0), where `top` is the action
  space's top speed: half the top speed is 80 % throttle.

A continuous action (-1..1) is first clipped and scaled linearly to the space's ranges.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.deepracer.action_space import ActionSpace
from sim.deepracer.files import ModelMetadata

# The navigation node's DEFAULT_SPEED_SCALES: throttle at the top speed and at half of it.
THROTTLE_AT_TOP = 1.0
THROTTLE_AT_HALF = 0.8


@dataclass(frozen=True)
class CarAction:
    """One action as the car drives it."""

    index: int | None  # discrete actions only
    steering_angle: float  # degrees, positive left, as in the action space
    speed: float  # m/s, as in the action space
    steering: float  # share of the servo's calibrated lock, -1..1, positive left
    throttle: float  # share of the car's max-speed setting, 0..1


@dataclass(frozen=True)
class CarMapping:
    """The navigation node's scales for one action space."""

    max_steering: float
    top_speed: float

    @classmethod
    def of(cls, space: ActionSpace) -> CarMapping:
        if space.kind == "discrete":
            steering = max(abs(action.steering_angle) for action in space.actions)
            speed = max(abs(action.speed) for action in space.actions)
        else:
            steering = space.steering_range[1]
            speed = space.speed_range[1]
        return cls(float(steering), float(speed))

    def steering(self, angle: float) -> float:
        # The car sends 0 when the largest angle is not positive (it logs an error).
        return angle / self.max_steering if self.max_steering > 0 else 0.0

    def throttle(self, speed: float) -> float:
        if self.top_speed <= 0:
            return 0.0
        a = (2.0 * THROTTLE_AT_TOP - 4.0 * THROTTLE_AT_HALF) / self.top_speed**2
        b = (4.0 * THROTTLE_AT_HALF - THROTTLE_AT_TOP) / self.top_speed
        return max(-1.0, min(1.0, a * speed * speed + b * speed))

    def action(self, steering_angle: float, speed: float, index: int | None = None) -> CarAction:
        return CarAction(
            index, steering_angle, speed, self.steering(steering_angle), self.throttle(speed)
        )


def car_actions(space: ActionSpace) -> tuple[CarAction, ...]:
    """The action table as the car drives it: every discrete action, or for a continuous
    space its corners and middle (steering low, 0, high at the lowest, middle and top
    speed)."""
    mapping = CarMapping.of(space)
    if space.kind == "discrete":
        return tuple(
            mapping.action(action.steering_angle, action.speed, index)
            for index, action in enumerate(space.actions)
        )
    low_steer, high_steer = space.steering_range
    low, high = space.speed_range
    angles = sorted({low_steer, min(max(0.0, low_steer), high_steer), high_steer})
    speeds = sorted({low, (low + high) / 2, high})
    return tuple(mapping.action(angle, speed) for speed in speeds for angle in angles)


def car_refusal(metadata: ModelMetadata) -> str | None:
    """Why the car cannot run this model, as the end of a sentence; None when it can."""
    if "vector" in metadata.sensors:
        return (
            "its sensor VECTOR is racer-tui's own (the car's place on the track as numbers), "
            "and a physical car has no such sensor; train a camera model for the car"
        )
    if "camera" not in metadata.sensors:
        return (
            "it has no camera, and DeepRacer's cars and simulator run only models with a "
            "camera among their sensors; add a camera to race it on a car"
        )
    if metadata.training_algorithm != "clipped_ppo":
        return (
            f"it was trained with {metadata.training_algorithm}, and racer-tui writes the car's "
            "graph for PPO models (clipped_ppo) only; clone it as a PPO model to export it"
        )
    return None


def car_export_notes(metadata: ModelMetadata) -> tuple[str, ...]:
    """What a racer should know before a car drives this export (one sentence each)."""
    if "lidar" in metadata.sensors or "sector_lidar" in metadata.sensors:
        return (
            "Its lidar input is racer-tui's scan (64 rays all round the car, up to 2 m, in "
            "metres) and its model_metadata.json sets no lidar_config, so a DeepRacer car feeds "
            "its own lidar setup: drive it slowly first.",
        )
    return ()

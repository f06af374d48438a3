"""Does a reward function pay for going faster? The reward a car would collect over one lap
of the centre line at each speed, before any training.

The most common DeepRacer reward mistake is a function that pays per step for being on the
road: a slow lap takes more steps, so it earns more, and the car learns to crawl. Here a
car drives the centre line at each speed (one pose per 1/15 s step, facing along the track,
progress and steps as they would be), the function is called at every step, and the lap's
total and the total per second are compared across speeds.

`lap_rewards` runs the racer's code, so only the reward probe's child process calls it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sim.car import STEP_HZ
from sim.reward_function import RewardFunction
from sim.simulation import TrackSimulation
from sim.track import Track

DEFAULT_SPEEDS = (1.0, 2.0, 3.0, 4.0)


@dataclass(frozen=True)
class LapPay:
    speed: float  # m/s
    steps: int  # steps in one lap at that speed
    total: float  # reward summed over the lap

    @property
    def per_second(self) -> float:
        return self.total / (self.steps / STEP_HZ)

    def to_json(self) -> dict[str, Any]:
        return {"speed": self.speed, "steps": self.steps, "total": self.total}


def lap_rewards(reward: RewardFunction, track: Track, speeds: tuple[float, ...]) -> list[LapPay]:
    """The lap's pay at each speed (see the module docstring)."""
    centre = track.centerline
    pays = []
    for speed in speeds:
        steps = max(2, int(np.ceil(centre.total_length / (speed / STEP_HZ))))
        s = np.arange(steps) * (speed / STEP_HZ)
        sim = TrackSimulation(track, steps)
        start = sim.start_position(0, 0)
        along = np.mod(start + s, centre.total_length)
        points = centre.point_at(along)
        directions = centre.direction_at(along)
        yaw = np.arctan2(directions[:, 1], directions[:, 0])
        sim.pose_all(points[:, 0], points[:, 1], yaw, speed, 0.0)
        fresh = reward.fresh()  # a new car: a function's own state starts again
        total = float(sum(fresh(params) for params in sim.all_params()[1:]))  # no prepare step
        pays.append(LapPay(speed, steps, total))
    return pays


def verdict(pays: list[LapPay]) -> str:
    """One sentence: does the function pay more for a faster lap?"""
    slow, fast = pays[0], pays[-1]
    tolerance = 0.01 * max(abs(slow.total), abs(fast.total))
    if fast.total > slow.total + tolerance:
        return (
            f"It pays more for a faster lap ({fast.total:.4g} at {fast.speed:g} m/s against "
            f"{slow.total:.4g} at {slow.speed:g} m/s): speed is rewarded."
        )
    if fast.total < slow.total - tolerance:
        return (
            f"It pays more for a slower lap ({slow.total:.4g} at {slow.speed:g} m/s against "
            f"{fast.total:.4g} at {fast.speed:g} m/s): a car trained on it learns to drive "
            "slowly. Pay in proportion to speed, for the progress made since the last step, "
            "or a bonus for a lap finished in few steps."
        )
    return (
        f"It pays about the same for a lap at any speed ({slow.total:.4g} to {fast.total:.4g}): "
        "nothing in it rewards speed."
    )

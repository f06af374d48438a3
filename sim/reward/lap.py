"""Does a reward function pay for going faster, and for which line? The reward a car would
collect over one lap at each speed, along the centre line and along the line the reference
driver drives, before any training.

The most common DeepRacer reward mistake is a function that pays per step for being on the
road: a slow lap takes more steps, so it earns more, and the car learns to crawl. The second
is a function that pays for the centre line: it pays less for the line a fast car drives,
inside the corners, as the reference driver does.

Here a car drives each line at each speed (one pose per 1/15 s step, facing along the line,
progress and steps as they would be), the function is called at every step, and the lap's
steps and totals are compared across speeds and lines.

`lap_rewards` runs the racer's code, so only the reward probe's child process calls it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sim.foundation.remedies import RemedyError
from sim.physics.car import STEP_HZ
from sim.physics.reference_driver import reference_lap
from sim.physics.simulation import TrackSimulation
from sim.reward.function import RewardFunction
from sim.tracks.geometry import PolylineProjector
from sim.tracks.track import Track

DEFAULT_SPEEDS = (1.0, 2.0, 3.0, 4.0)
CENTRE_LINE = "centre line"
# as the reference driver drives it (sim.physics.reference_driver)
REFERENCE_LINE = "reference line"
LINES = (CENTRE_LINE, REFERENCE_LINE)


@dataclass(frozen=True)
class LapPay:
    speed: float  # m/s
    steps: int  # steps in one lap at that speed
    total: float  # reward summed over the lap
    line: str = CENTRE_LINE
    rewards: tuple[float, ...] = ()  # each step's reward, in order along the lap

    @property
    def per_second(self) -> float:
        return self.total / (self.steps / STEP_HZ)

    def to_json(self) -> dict[str, Any]:
        return {
            "line": self.line,
            "speed": self.speed,
            "steps": self.steps,
            "total": self.total,
            "rewards": list(self.rewards),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> LapPay:
        return cls(
            float(data["speed"]),
            int(data["steps"]),
            float(data["total"]),
            str(data.get("line", CENTRE_LINE)),
            tuple(float(value) for value in data.get("rewards", ())),
        )


class NoLapError(RemedyError):
    """A line with no lap to drive on this track (the reference driver does not finish one)."""


def line_path(track: Track, line: str) -> PolylineProjector:
    """The closed line a lap drives, starting across the road from the start line."""
    if line == CENTRE_LINE:
        return track.centerline
    if line == REFERENCE_LINE:
        lap = reference_lap(track)
        if not lap.completed:
            raise NoLapError(f"the reference driver does not finish a lap of {track.name}")
        # Closed back to the standing start; steps too short to matter (the first
        # instants of the start) are dropped, as a polyline cannot repeat a point.
        points = np.vstack([lap.path, lap.path[:1]])
        keep = np.concatenate([[True], np.hypot(*np.diff(points, axis=0).T) > 1e-6])
        return PolylineProjector(points[keep])
    raise ValueError(f"no line named {line!r}; the lines are {', '.join(LINES)}")


def lap_rewards(
    reward: RewardFunction,
    track: Track,
    speeds: tuple[float, ...],
    lines: tuple[str, ...] = (CENTRE_LINE,),
) -> list[LapPay]:
    """The lap's pay on each line at each speed (see the module docstring), line by line;
    a line with no lap on this track (`NoLapError`) is left out."""
    pays = []
    for line in lines:
        try:
            path = line_path(track, line)
        except NoLapError:
            continue
        for speed in speeds:
            steps = max(2, int(np.ceil(path.total_length / (speed / STEP_HZ))))
            along = np.mod(np.arange(steps) * (speed / STEP_HZ), path.total_length)
            points = path.point_at(along)
            directions = path.direction_at(along)
            yaw = np.arctan2(directions[:, 1], directions[:, 0])
            sim = TrackSimulation(track, steps)
            sim.pose_all(points[:, 0], points[:, 1], yaw, speed, 0.0)
            sim.steps[:] = 1 + np.arange(steps)  # the steps driven, on whichever line
            fresh = reward.fresh()  # a new car: a function's own state starts again
            # Step 1 is DeepRacer's prepare step: the function is not called on it.
            rewards = tuple(float(fresh(params)) for params in sim.all_params()[1:])
            pays.append(LapPay(speed, steps, float(sum(rewards)), line, rewards))
    return pays


def verdict(pays: list[LapPay]) -> str:
    """One sentence: does the function pay more for a faster lap? (On the first line
    `pays` holds, from its slowest lap to its fastest.)"""
    on_line = [pay for pay in pays if pay.line == pays[0].line]
    slow, fast = on_line[0], on_line[-1]
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


def line_verdict(pays: list[LapPay]) -> str | None:
    """One sentence: at the fastest speed, does it pay more for the reference driver's line
    or for the centre line? None without a lap of each."""
    fastest = max(pay.speed for pay in pays)
    by_line = {pay.line: pay for pay in pays if pay.speed == fastest}
    centre, driven = by_line.get(CENTRE_LINE), by_line.get(REFERENCE_LINE)
    if centre is None or driven is None:
        return None
    tolerance = 0.01 * max(abs(centre.total), abs(driven.total))
    both = f"({driven.total:.4g} against {centre.total:.4g} at {fastest:g} m/s)"
    if driven.total > centre.total + tolerance:
        return f"It pays more for the reference driver's line than for the centre line {both}."
    if driven.total < centre.total - tolerance:
        return (
            "It pays less for the reference driver's line than for the centre line "
            f"{both}: it holds a car to the centre, where a lap at that speed takes "
            f"{centre.steps} steps against {driven.steps} on the reference driver's line."
        )
    return f"It pays about the same for the reference driver's line as for the centre line {both}."

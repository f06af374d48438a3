"""Where a sim-trace row says the car is: DeepRacer's row timing.

In DeepRacer's sim-trace the pose of a row is one row late: the pose of row i+1 is the
car's state at row i's `tstamp` (checked on the console's, DeepRacer-for-Cloud's and
DeepRacer-on-AWS traces; `sim.calibration` relies on the same fact). So each row shows
where the car was when the step before it ended, which is where the row's own command was
sent from, and the row that ends an episode or puts a car back shows the pose that did it
(an off-track row shows the car off the road, a lap's last row the line crossed). The first
row of an episode shows the start.

racer-tui's writers (`sim.training.logbook` for training, `sim.training.evaluation` for
trials) tell a `RowPoses` before each step and ask it after the step for each row's
pose. Only what describes the pose moves: the point ahead, the heading, all four wheels on
the road, progress and the segment the point is on. The command, the
reward and the status stay with the step they belong to, so an episode's rewards still sum
to its metrics row and its last row still says how it ended.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.simulation import TrackSimulation


@dataclass(frozen=True)
class TracePose:
    """The pose columns of every car of a simulation at one moment (copies)."""

    ahead: NDArray[np.float64]  # (N, 2): DeepRacer's point 0.14 m ahead of the car
    heading_deg: NDArray[np.float64]
    wheels_on: NDArray[np.bool_]  # all four wheels on the road
    progress: NDArray[np.float64]
    segment: NDArray[np.int64]  # centre-line segment the point ahead is on

    @classmethod
    def of(cls, sim: TrackSimulation) -> TracePose:
        return cls(
            ahead=np.array(sim.ahead, dtype=np.float64),
            heading_deg=np.array(sim.heading_deg, dtype=np.float64),
            wheels_on=np.asarray(np.all(sim.wheels_on, axis=1), dtype=np.bool_),
            progress=np.array(sim.progress, dtype=np.float64),
            segment=np.array(sim.segment, dtype=np.int64),
        )

    def row_pose(self, after: TracePose, sim: TrackSimulation) -> TracePose:
        """The pose each car's row of the step just taken shows: this one (taken before the
        step), or `after` for cars whose step ended an episode or put them back."""
        event = np.asarray(sim.status) != EpisodeStatus.IN_PROGRESS
        if not event.any():
            return self
        column = event[:, None]
        return TracePose(
            ahead=np.where(column, after.ahead, self.ahead),
            heading_deg=np.where(event, after.heading_deg, self.heading_deg),
            wheels_on=np.where(event, after.wheels_on, self.wheels_on),
            progress=np.where(event, after.progress, self.progress),
            segment=np.where(event, after.segment, self.segment),
        )


class RowPoses:
    """The poses of a step's rows: told the simulation before the step, asked after it."""

    def __init__(self) -> None:
        self._before: TracePose | None = None

    def before_step(self, sim: TrackSimulation) -> None:
        self._before = TracePose.of(sim)

    def after_step(self, sim: TrackSimulation) -> TracePose:
        """Each car's row pose for the step just taken (see `TracePose.row_pose`)."""
        after = TracePose.of(sim)
        before = self._before if self._before is not None else after
        return before.row_pose(after, sim)

"""Every step of every car, kept until its episode ends: the rows a training log is made of.

A `StepRecorder` watches a `BatchedDeepRacer` (it is its `StepWatcher`) and keeps, per car,
one row per step: the step's own action, reward and status, and the pose as DeepRacer's row
timing shows it (`sim.training.trace_pose`: where the car was when the step began, or where
the step left it if it ended the episode): DeepRacer's point 0.14 m ahead of the car's
centre, heading, all four wheels on the road and progress. When a car's episode ends the
rows come out as one `EndedEpisode`, taken before the car restarts.

The recorder runs where the cars run: in the trainer's process, or in a simulation process
of a training spread across cores (sim.training.shards), which sends its ended episodes to
the trainer's `Logbook` with each step. An ended episode is plain data (numpy and tuples),
so it pickles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.physics.simulation import TrackSimulation
from sim.training.trace_pose import RowPoses

# Columns of a row (the segment becomes the closest waypoint only for the rows written).
X, Y, YAW, STEER, THROTTLE, ACTION, REWARD, WHEELS, PROGRESS, SEGMENT = range(10)
COLUMNS = 10

# Where a car's objects stood when its episode ended: (x, y, heading) of each.
ObjectPoses = tuple[tuple[float, float, float], ...]


@dataclass(frozen=True)
class EndedEpisode:
    """One car's finished episode: every step's row, how it ended, and its objects."""

    car: int  # the car's number in the whole training fleet
    status: str
    rows: NDArray[np.float64]  # (steps, COLUMNS)
    objects: ObjectPoses | None = None  # None: the car drove without objects
    objects_are_cars: bool = False

    @property
    def steps(self) -> int:
        return len(self.rows)


class StepRecorder:
    """The step rows of `cars` cars (numbered from `first_car` in the fleet)."""

    def __init__(self, cars: int, *, discrete: bool, first_car: int = 0) -> None:
        self.cars = cars
        self.first_car = first_car
        self._discrete = discrete
        self._buffer = np.zeros((cars, 256, COLUMNS))
        self._step = np.zeros((cars, COLUMNS))  # one step of the cars, before it is stored
        self._step[:, ACTION] = -1.0  # continuous actions have no index
        self._rows = np.arange(cars)
        self._poses = RowPoses()
        self.ended: list[EndedEpisode] = []  # since they were last taken

    def before_step(self, sim: TrackSimulation) -> None:
        """Note where every car is before the step (a row's pose is one row late)."""
        self._poses.before_step(sim)

    def after_step(self, sim: TrackSimulation, actions: np.ndarray, rewards: np.ndarray) -> None:
        """Record the step; called by the env before finished cars restart."""
        row = sim.steps - 1
        if int(row.max()) >= self._buffer.shape[1]:
            self._grow(int(row.max()) + 1)
        pose = self._poses.after_step(sim)
        # Column by column into one block, then one store: a few microseconds per step.
        step = self._step
        step[:, X : Y + 1] = pose.ahead
        step[:, YAW] = pose.heading_deg
        step[:, STEER] = sim.steering_cmd
        step[:, THROTTLE] = sim.speed_cmd
        if self._discrete:
            step[:, ACTION] = np.reshape(actions, self.cars)
        step[:, REWARD] = rewards
        step[:, WHEELS] = pose.wheels_on
        step[:, PROGRESS] = pose.progress
        step[:, SEGMENT] = pose.segment
        self._buffer[self._rows, row] = step
        done = sim.done
        if not done.any():
            return
        objects = sim.objects
        for car in np.flatnonzero(done).tolist():
            steps = int(sim.steps[car])
            poses: ObjectPoses | None = None
            if objects is not None:
                stacked = np.stack([objects.x[car], objects.y[car], objects.heading[car]], axis=1)
                poses = tuple((x, y, heading) for x, y, heading in stacked.tolist())
            self.ended.append(
                EndedEpisode(
                    self.first_car + car,
                    str(sim.status[car]),
                    self._buffer[car, :steps].copy(),
                    poses,
                    objects is not None and objects.shape.is_car,
                )
            )

    def take(self) -> list[EndedEpisode]:
        ended, self.ended = self.ended, []
        return ended

    def _grow(self, needed: int) -> None:
        size = self._buffer.shape[1]
        while size < needed:
            size *= 2
        grown = np.zeros((self.cars, size, COLUMNS))
        grown[:, : self._buffer.shape[1]] = self._buffer
        self._buffer = grown

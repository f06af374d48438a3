"""The other racing cars of a head-to-head race, as each car's objects (docs/deepracer/
head-to-head-simapp.md).

In simapp's HEAD_TO_MODEL every racing car is an object of every other: it is drawn in
their cameras, seen by their lidar, listed in their reward params' object keys, and judged
by the crash rule boxes and bot cars are judged by (a corner of one car's footprint inside
the other's rectangle, 0.3235 x 0.1961 m, `BOT_CAR_DIMENSION`).

A head-to-head race drives each car in a simulation of its own, with the time trial's
one-car physics (the same laps a car drives alone), and couples them here: car i's objects
are the other cars, in grid order (simapp registers the racing agents first, in index
order, and leaves the car's own name out), wherever those cars are. The race moves every
car first and then judges crashes (`Grid.crashes`, every pair at once), so no car is
judged against where another was before the step; a simulation never judges a crash with a
rival itself.

What simapp does with a crash between two racing cars, and so the race:
- only the car whose progress is lower (the car behind) crashed; the car in front drives on
  and is not counted;
- a car serving a penalty cannot be run into (simapp's blink effect makes it
  non-collidable), and is not judged itself (only cars in their run phase are).
racer-tui departs in one place: "behind" compares where the cars are in the race (laps and
the distance into the lap), where simapp compares the progress into the lap alone, modulo
100. simapp's way makes a car about to lap its rival, or still behind the start line on
the grid, the car in front.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec, Fleet
from sim.physics.objects.field import BOT_CAR_SHAPE, ObjectField, corners_inside
from sim.tracks.track import Track

# simapp gives racing cars the bot cars' rectangle (`ObstacleDimensions.BOT_CAR_DIMENSION`).
RIVAL_SHAPE = BOT_CAR_SHAPE
# Every car's x, y and heading (radians), in grid order.
CarPoses = tuple[list[float], list[float], list[float]]


@dataclass
class Grid:
    """What every car's field shares: the cars, where each is in the race, who is held."""

    fleets: Sequence[Fleet]  # one car each, in grid order
    track_length: float
    # Metres from the start line, laps included (the running order; modulo the track's
    # length, where each car is on it: which of two cars that touch is behind).
    standing: FloatArray
    # Cars serving a penalty: the others drive through them, and they are not judged.
    ghost: NDArray[np.bool_]

    @classmethod
    def of(cls, fleets: Sequence[Fleet], track: Track) -> Grid:
        count = len(fleets)
        return cls(list(fleets), track.length, np.zeros(count), np.zeros(count, dtype=bool))

    def poses(self) -> CarPoses:
        """Where every car stands now: x, y and heading lists, in grid order."""
        fleets = self.fleets
        return (
            [float(fleet.x[0]) for fleet in fleets],
            [float(fleet.y[0]) for fleet in fleets],
            [float(fleet.yaw[0]) for fleet in fleets],
        )

    def crashes(
        self, drivers: Sequence[int], car_spec: CarSpec, poses: CarPoses | None = None
    ) -> dict[int, list[int]]:
        """For each car in `drivers`, the cars it ran into from behind this step (grid
        indices): a corner of it inside their rectangle, neither of them held, it behind
        them on the track. Every pair is judged in one pass: a race's cars are mostly apart,
        and the close pairs share one crash test. `poses`: the grid's, if read already."""
        x, y, yaw = self.poses() if poses is None else poses
        limit = RIVAL_SHAPE.reach(car_spec) ** 2
        ghost = self.ghost.tolist()
        pairs = [
            (me, other)
            for me in drivers
            if not ghost[me]
            for other in range(len(x))
            if other != me
            and not ghost[other]
            and (x[me] - x[other]) ** 2 + (y[me] - y[other]) ** 2 <= limit
        ]
        found: dict[int, list[int]] = {me: [] for me in drivers}
        if not pairs:
            return found
        mine, theirs = (np.array(side, dtype=np.intp) for side in zip(*pairs, strict=True))
        table = np.array([x, y, yaw])
        hits = corners_inside(
            car_spec,
            (table[0, mine], table[1, mine], table[2, mine]),
            RIVAL_SHAPE,
            (table[0, theirs, None], table[1, theirs, None], table[2, theirs, None]),
        )[:, 0]
        for (me, other), hit in zip(pairs, hits.tolist(), strict=True):
            if hit and self.behind(me, other):
                found[me].append(other)
        return found

    def behind(self, me: int, other: int) -> bool:
        """Car `me` is behind car `other` on the track, the short way round: laps do not
        count, so a car that runs into the one it is lapping is the car behind, and so is
        a car just short of the line that runs into one just past it."""
        length = self.track_length  # the race's standing is measured along it
        ahead = (float(self.standing[other]) - float(self.standing[me])) % length
        return 0.0 < ahead < length / 2.0


class RivalField(ObjectField):
    """Car `index`'s objects (its simulation has that one car): the grid's other cars."""

    def __init__(self, track: Track, index: int, grid: Grid) -> None:
        cars = len(grid.fleets)
        if cars < 2:
            raise ValueError("a head-to-head race needs at least two cars")
        super().__init__(track, cars - 1, 1, RIVAL_SHAPE)
        self.index = index
        self.grid = grid
        self._others = [j for j in range(cars) if j != index]
        self._placed_at: list[float] = []
        self._measured = False
        self.follow()

    def draw(self, car: int, backwards: bool = False) -> None:
        self.follow()

    def follow(self, poses: CarPoses | None = None) -> None:
        """The objects where the other cars are now (`poses`: the grid's, read once for
        every car's field)."""
        x, y, heading = self.grid.poses() if poses is None else poses
        others = self._others
        placed = [x[j] for j in others] + [y[j] for j in others] + [heading[j] for j in others]
        if placed == self._placed_at:
            return  # nobody moved (every car held): the camera keeps its drawing
        self._placed_at = placed
        count = len(others)
        self.x = np.array([placed[:count]])
        self.y = np.array([placed[count : 2 * count]])
        self.heading = np.array([placed[2 * count :]])
        self.placed += 1  # the camera draws them anew
        self._measured = False

    def _measure_rivals(self) -> None:
        """Along and across the centre line: only the reward params read it."""
        if self._measured:
            return
        self.measure_where_they_stand()
        self._measured = True

    def all_params(
        self,
        ahead_s: list[float],
        ahead_x: list[float],
        ahead_y: list[float],
        heading_deg: list[float],
    ) -> list[dict[str, Any]]:
        self._measure_rivals()
        return super().all_params(ahead_s, ahead_x, ahead_y, heading_deg)

    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        # The race judges crashes between its cars once all have moved (`crashed_into`).
        return np.zeros(len(x), dtype=bool)

    def crashed_into(self, car_spec: CarSpec) -> list[int]:
        """The cars this car ran into from behind this step (`Grid.crashes`)."""
        return self.grid.crashes([self.index], car_spec)[self.index]

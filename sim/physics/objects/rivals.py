"""The other racing cars of a head-to-head race, as each car's objects (docs/deepracer/
head-to-head-simapp.md).

In simapp's HEAD_TO_MODEL every racing car is an object of every other: it is drawn in
their cameras, seen by their lidar, listed in their reward params' object keys, and judged
by the crash rule boxes and bot cars are judged by (a corner of one car's footprint inside
the other's rectangle, 0.3235 x 0.1961 m, `BOT_CAR_DIMENSION`). So here: car i's objects are
the other cars, in their race order (simapp registers the racing agents first, in index
order, and leaves the car's own name out), moved to where those cars are after every step.

What simapp does with a crash between two racing cars, and so this field:
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

import numpy as np
from numpy.typing import NDArray

from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec, Fleet
from sim.physics.objects.field import BOT_CAR_SHAPE, ObjectField
from sim.tracks.track import Track

# simapp gives racing cars the bot cars' rectangle (`ObstacleDimensions.BOT_CAR_DIMENSION`).
RIVAL_SHAPE = BOT_CAR_SHAPE


class RivalField(ObjectField):
    """For each of a race's `cars` cars, the others, following `fleet` (the race's cars)."""

    def __init__(self, track: Track, cars: int, fleet: Fleet) -> None:
        if cars < 2:
            raise ValueError("a head-to-head race needs at least two cars")
        super().__init__(track, cars - 1, cars, RIVAL_SHAPE)
        self._fleet = fleet
        # (cars, cars - 1): car i's objects are the other cars, in race order.
        self.others = np.array([[j for j in range(cars) if j != i] for i in range(cars)])
        # Cars serving a penalty: the others drive through them, and they are not judged.
        self.ghost = np.zeros(cars, dtype=bool)
        # Where each car is in the race (laps and distance into the lap, metres): the
        # engine keeps it, and the car with less of it crashed.
        self.standing = np.zeros(cars)
        self.follow()

    def draw(self, car: int, backwards: bool = False) -> None:
        self.follow()

    def advance(self, seconds: float) -> None:
        self.follow()  # the cars have moved: their rivals' objects with them

    def follow(self) -> None:
        """Every car's objects where the other cars are now."""
        fleet, others = self._fleet, self.others
        x, y, yaw = np.asarray(fleet.x), np.asarray(fleet.y), np.asarray(fleet.yaw)
        centre = self.lanes.centre
        points = np.column_stack([x, y])
        segment, t, foot = centre.project(points)
        distance = centre.arc_length(segment, t)
        vectors = centre.vectors[segment]
        relative = points - foot
        cross = vectors[:, 0] * relative[:, 1] - vectors[:, 1] * relative[:, 0]
        # Left of the centre line, driving the track's way (simapp: inside the inner half,
        # flipped on a clockwise track, which is the same side).
        left = cross > 0.0
        from_centre = np.hypot(relative[:, 0], relative[:, 1])
        self.x, self.y, self.heading = x[others], y[others], yaw[others]
        self.distance, self.left, self.from_centre = (
            distance[others],
            left[others],
            from_centre[others],
        )
        self.placed += 1  # the camera draws them anew

    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        """Cars that ran into a rival this step and are behind it (see the docstring)."""
        hits = self.hits(x, y, yaw, car_spec) & ~self.ghost[self.others]
        behind = self.standing[:, None] < self.standing[self.others]
        return np.asarray((hits & behind).any(axis=1) & ~self.ghost)

    def rivals_hit(
        self, car: int, x: FloatArray, y: FloatArray, yaw: FloatArray, car_spec: CarSpec
    ) -> list[int]:
        """The cars `car` is touching now (race indices), ghosts left out."""
        row = self.hits(x, y, yaw, car_spec)[car] & ~self.ghost[self.others[car]]
        return [int(other) for other in self.others[car][row]]

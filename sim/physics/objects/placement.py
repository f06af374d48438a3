"""Where an object-avoidance race's boxes stand, episode by episode, as DeepRacer places them.

Distances are metres along the centre line from its first waypoint. Fixed positions
(OBJECT_POSITIONS) are progress x length. Otherwise N boxes start evenly spaced from the
minimum distance to 1 m before the line; randomised, each is drawn again, in a shuffled
order, uniformly between its neighbours (keeping the minimum distance from each), and
takes a random lane; not randomised, the lanes alternate inner, outer, ... A box stands in
the middle of its lane, where the lane passes the centre line's point, facing along it.

One difference from simapp, on purpose: simapp turns MIN_DISTANCE_BETWEEN_OBSTACLES from a
percentage into metres again at every reset, overwriting the setting, so on any track
shorter than 100 m the spacing shrinks towards nothing within a few episodes
(docs/deepracer-objects.md). racer-tui converts it once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from sim.foundation.arrays import FloatArray
from sim.physics.objects.settings import Lane, ObstacleSettings
from sim.tracks.geometry import PolylineProjector
from sim.tracks.track import Track

# Metres kept free before the start line (simapp's end of the evenly spaced range).
CLEAR_BEFORE_LINE: Final = 1.0
# A box as sensors see it (simapp's box_obstacle model, 0.25 m high) ...
BOX_MODEL_LENGTH: Final = 0.4  # along the road
BOX_MODEL_WIDTH: Final = 0.3
BOX_HEIGHT: Final = 0.25
# ... and as DeepRacer's crash check sees it: 0.1 m more each way.
BOX_LENGTH: Final = 0.5
BOX_WIDTH: Final = 0.4
# A bot car: DeepRacer's car body, whose crash footprint is simapp's BOT_CAR_DIMENSION (the
# racecar's too) and whose height is the car's shell over the ground (about 0.16 m).
BOT_CAR_LENGTH: Final = 0.3235
BOT_CAR_WIDTH: Final = 0.1961
BOT_CAR_HEIGHT: Final = 0.16


@dataclass(frozen=True)
class ObjectPose:
    x: float
    y: float
    heading: float  # radians, along the lane
    distance: float  # metres along the centre line from its first waypoint
    lane: Lane


@dataclass(frozen=True, eq=False)
class Lanes:
    """The two lane lines of a track: midway between the centre line and each border."""

    centre: PolylineProjector
    inner: PolylineProjector
    outer: PolylineProjector

    @classmethod
    def of(cls, track: Track) -> Lanes:
        return cls(track.centerline, track.inner_lane, track.outer_lane)

    def pose(self, distance: float, lane: Lane) -> ObjectPose:
        """Where lane `lane` passes the centre line's point `distance` along it."""
        line = self.inner if lane is Lane.INNER else self.outer
        point = self.centre.point_at(np.array([distance]))
        segment, t, foot = line.project(point)
        along = line.arc_length(segment, t)
        dx, dy = line.direction_at(along)[0]
        return ObjectPose(
            float(foot[0, 0]), float(foot[0, 1]), math.atan2(dy, dx), float(distance), lane
        )


def obstacle_poses(
    settings: ObstacleSettings, lanes: Lanes, rng: np.random.Generator
) -> list[ObjectPose]:
    """The boxes of one episode (draw again for the next when `settings.randomize`)."""
    length = lanes.centre.total_length
    if settings.positions:
        return [lanes.pose(progress * length, lane) for progress, lane in settings.positions]
    distances = obstacle_distances(settings, length, rng)
    if settings.randomize:
        kinds = [Lane.INNER if rng.random() < 0.5 else Lane.OUTER for _ in distances]
    else:
        kinds = [Lane.INNER if i % 2 == 0 else Lane.OUTER for i in range(len(distances))]
    return [lanes.pose(float(d), lane) for d, lane in zip(distances, kinds, strict=True)]


def obstacle_distances(
    settings: ObstacleSettings, length: float, rng: np.random.Generator
) -> FloatArray:
    """Where along the centre line the boxes stand (see the module docstring)."""
    gap = settings.min_distance_percent / 100.0 * length
    end = length - CLEAR_BEFORE_LINE
    distances = np.linspace(gap, end, settings.count)
    if not settings.randomize or settings.count == 0:
        return distances
    for i in rng.permutation(settings.count):
        low = gap if i == 0 else distances[i - 1] + gap
        high = end if i == settings.count - 1 else distances[i + 1] - gap
        if low < high:
            distances[i] = rng.uniform(low, high)
    return distances

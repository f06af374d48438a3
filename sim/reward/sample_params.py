"""A hand-made, DeepRacer-complete reward `params` dict, for quick checks and tests.

The car is on the first straight of a small stadium-shaped loop (two 6 m straights joined by
half circles of radius 1.5 m, driven counter-clockwise from the origin along +x). Every value
follows DeepRacer's rules and types: `x`, `y`, `progress` and the centre-line figures describe
the point 0.14 m ahead of the car's centre, `heading` is in degrees from +x, and `speed` /
`steering_angle` are the commanded action. By default two boxes stand on the straight, neither
close to the car in its lane, so functions written for object avoidance run too.

`PARAM_KEYS` is the one definition of the key set: the simulator builds its params from it.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from sim.deepracer.vocabulary import no_objects

PARAM_KEYS: tuple[str, ...] = (
    "all_wheels_on_track",
    "x",
    "y",
    "heading",
    "distance_from_center",
    "is_left_of_center",
    "track_width",
    "track_length",
    "waypoints",
    "closest_waypoints",
    "progress",
    "steps",
    "speed",
    "steering_angle",
    "is_reversed",
    "is_offtrack",
    "is_crashed",
    "projection_distance",
    "sim_time",
    "closest_objects",
    "objects_location",
    "objects_left_of_center",
    "objects_speed",
    "objects_heading",
    "objects_distance",
    "objects_distance_from_center",
    "object_in_camera",
)


STRAIGHT_LENGTH = 6.0
TURN_RADIUS = 1.5
TRACK_WIDTH = 0.76
# Waypoint spacing: 0.5 m on the straights, 15 degrees on the half circles.
_STRAIGHT_SEGMENTS = 12
_TURN_SEGMENTS = 12

# The point the params describe (0.14 m ahead of the car's centre): 2.1 m along the first
# straight, 5 cm right of the centre line, driving straight along it.
CAR_X = 2.1
CAR_Y = -0.05
STEPS = 20
STEP_RATE_HZ = 15.0

# Boxes sit in the middle of a lane, as DeepRacer places its obstacles.
LANE_OFFSET = TRACK_WIDTH / 4
# One box behind the car in its own lane and one ahead in the other lane: every object key has
# a real value, yet nothing is close enough ahead to change an avoidance reward.
SAMPLE_OBJECTS: tuple[tuple[float, float], ...] = ((0.6, -LANE_OFFSET), (4.1, LANE_OFFSET))

# DeepRacer's camera sees 1.13 rad across (simapp `frustum.py`); objects within half of that
# either side of the heading and ahead of the car count as `object_in_camera`.
_CAMERA_HALF_ANGLE = 1.13 / 2.0


def _stadium_waypoints() -> list[tuple[float, float]]:
    points: list[tuple[float, float]] = []
    step = STRAIGHT_LENGTH / _STRAIGHT_SEGMENTS
    points += [(i * step, 0.0) for i in range(_STRAIGHT_SEGMENTS + 1)]
    for i in range(1, _TURN_SEGMENTS + 1):
        angle = -math.pi / 2 + math.pi * i / _TURN_SEGMENTS
        points.append(
            (STRAIGHT_LENGTH + TURN_RADIUS * math.cos(angle), TURN_RADIUS * (1 + math.sin(angle)))
        )
    points += [(STRAIGHT_LENGTH - i * step, 2 * TURN_RADIUS) for i in range(1, _STRAIGHT_SEGMENTS)]
    for i in range(_TURN_SEGMENTS + 1):
        angle = math.pi / 2 + math.pi * i / _TURN_SEGMENTS
        points.append((TURN_RADIUS * math.cos(angle), TURN_RADIUS * (1 + math.sin(angle))))
    # Exact closing row, as in DeepRacer's .npy loops (cos/sin leave ~1e-16 residue).
    points[-1] = points[0]
    return points


_WAYPOINTS = _stadium_waypoints()
TRACK_LENGTH = math.fsum(math.dist(a, b) for a, b in itertools.pairwise(_WAYPOINTS))


def _object_params(objects: Sequence[tuple[float, float]]) -> dict[str, object]:
    """Object keys for boxes on the first straight, measured as DeepRacer measures them."""
    for x, y in objects:
        if not (0.0 <= x <= STRAIGHT_LENGTH and abs(y) <= TRACK_WIDTH / 2):
            raise ValueError(
                f"sample object ({x}, {y}) is not on the first straight; use 0 <= x <= "
                f"{STRAIGHT_LENGTH} and -{TRACK_WIDTH / 2} <= y <= {TRACK_WIDTH / 2}"
            )
    if not objects:
        return no_objects()
    # On the first straight the distance along the centre line from the start is just x.
    distances = [float(x) for x, _ in objects]
    ahead = [(d - CAR_X) % TRACK_LENGTH for d in distances]
    behind = [(CAR_X - d) % TRACK_LENGTH for d in distances]
    next_index = min(range(len(objects)), key=ahead.__getitem__)
    previous_index = min(range(len(objects)), key=behind.__getitem__)
    in_camera = any(
        x > CAR_X and math.atan2(abs(y - CAR_Y), x - CAR_X) <= _CAMERA_HALF_ANGLE
        for x, y in objects
    )
    return {
        "closest_objects": [previous_index, next_index],
        "objects_location": [(float(x), float(y)) for x, y in objects],
        "objects_left_of_center": [y > 0 for _, y in objects],
        # Stationary boxes: DeepRacer reports speed 0 and heading 0 for them.
        "objects_speed": [0.0 for _ in objects],
        "objects_heading": [0.0 for _ in objects],
        "objects_distance": distances,
        "objects_distance_from_center": [abs(float(y)) for _, y in objects],
        "object_in_camera": in_camera,
    }


def sample_params(*, objects: Sequence[tuple[float, float]] = SAMPLE_OBJECTS) -> dict[str, object]:
    """A fresh params dict for a car on a straight, as DeepRacer would pass it.

    `objects` places stationary boxes at (x, y) on the first straight (x 0..6 m along it,
    y left of the centre line positive); pass `()` for a time trial with no objects.
    """
    step = STRAIGHT_LENGTH / _STRAIGHT_SEGMENTS
    previous_waypoint = int(CAR_X // step)
    params: dict[str, object] = {
        "all_wheels_on_track": True,
        "x": CAR_X,
        "y": CAR_Y,
        "heading": 0.0,
        "distance_from_center": abs(CAR_Y),
        "is_left_of_center": CAR_Y > 0,
        "track_width": TRACK_WIDTH,
        "track_length": TRACK_LENGTH,
        "waypoints": list(_WAYPOINTS),
        "closest_waypoints": [previous_waypoint, previous_waypoint + 1],
        # The episode started at waypoint 0, so progress is the distance driven from there.
        "progress": 100.0 * CAR_X / TRACK_LENGTH,
        "steps": STEPS,
        "speed": 2.0,
        "steering_angle": 0.0,
        "is_reversed": False,
        "is_offtrack": False,
        "is_crashed": False,
        "projection_distance": CAR_X,
        # Steps count from 1, so step 20 comes 19 ticks after the episode's first.
        "sim_time": (STEPS - 1) / STEP_RATE_HZ,
    }
    params.update(_object_params(objects))
    return {key: params[key] for key in PARAM_KEYS}

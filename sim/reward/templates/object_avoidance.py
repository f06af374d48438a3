"""Stay on the road and keep clear of the next object in
your way (object avoidance and head-to-bot races).

Each step pays for two things, the second weighted four
times the first:
- the road: 1.0 with all four wheels on the track and
  the car's centre at least 5 cm inside the edge, almost
  nothing otherwise;
- clearance: the next object ahead, when it is in the
  car's way, costs pay as the car closes in (full pay
  from 0.8 m away, half from 0.5 m, a fifth from 0.3 m,
  and almost nothing nearer, where the car is about to
  hit it). In the way means less than 0.4 m across the
  road between the car's centre and the object's: a
  box's crash zone reaches 0.2 m to each side of it and
  the car is 0.2 m wide, so just over the centre line
  from a box in the other lane is still in its way.

What it teaches: move well clear of an object before
reaching it rather than brake into it.

Where it stops helping: it measures the gap in a
straight line, not along the road, and only to the next
object. With no objects on the track (a time trial) it
pays the road part and full clearance on every step, so
it teaches no more than stay_inside_borders.
"""

import math

EDGE_MARGIN = 0.05  # metres, car centre to road edge
# At least this many metres from the next object in the
# car's way, and the clearance pay there.
CLEARANCE = ((0.8, 1.0), (0.5, 0.5), (0.3, 0.2))
# Metres across the road within which an object is in
# the car's way.
IN_THE_WAY = 0.4
ALMOST_NOTHING = 0.001
ROAD_WEIGHT = 1.0
CLEARANCE_WEIGHT = 4.0


def road_pay(params):
    half_width = params["track_width"] / 2
    room = half_width - params["distance_from_center"]
    wheels_on = params["all_wheels_on_track"]
    if wheels_on and room >= EDGE_MARGIN:
        return 1.0
    return ALMOST_NOTHING


def across(params):
    """The car's offset from the centre line, left +."""
    side = 1 if params["is_left_of_center"] else -1
    return side * params["distance_from_center"]


def object_across(params, index):
    """An object's offset from the centre line, left +; None
    where the params do not say it (DeepRacer on AWS checks
    a reward function on states without that key)."""
    distances = params.get("objects_distance_from_center")
    if distances is None:
        return None
    side = 1 if params["objects_left_of_center"][index] else -1
    return side * distances[index]


def clearance_pay(params):
    objects = params["objects_location"]
    if not objects:
        return 1.0
    ahead = params["closest_objects"][1]
    offset = object_across(params, ahead)
    if offset is not None and abs(across(params) - offset) >= IN_THE_WAY:
        return 1.0  # it passes beside the car
    object_x, object_y = objects[ahead]
    gap_x = params["x"] - object_x
    gap_y = params["y"] - object_y
    gap = math.hypot(gap_x, gap_y)
    for at_least, pay in CLEARANCE:
        if gap >= at_least:
            return pay
    return ALMOST_NOTHING


def reward_function(params):
    road = ROAD_WEIGHT * road_pay(params)
    clearance = CLEARANCE_WEIGHT * clearance_pay(params)
    return float(ALMOST_NOTHING + road + clearance)

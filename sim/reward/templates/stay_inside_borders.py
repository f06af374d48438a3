"""Stay on the road: a step with all four wheels on the
track, and the car's centre at least 5 cm inside the
edge, pays 1.0; any other step pays almost nothing.

What it teaches: never leave the track. It is the
gentlest start, since anywhere on the road is as good as
anywhere else, so the car finds its own line.

Where it stops helping: it pays for surviving, not for
being quick, so a car trained only on it is safe and
slow. Add pay for speed or progress once laps complete.
"""

EDGE_MARGIN = 0.05  # metres, car centre to road edge
ON_THE_ROAD = 1.0
OFF_THE_ROAD = 0.001


def reward_function(params):
    half_width = params["track_width"] / 2
    room = half_width - params["distance_from_center"]
    wheels_on = params["all_wheels_on_track"]
    if wheels_on and room >= EDGE_MARGIN:
        return ON_THE_ROAD
    return OFF_THE_ROAD

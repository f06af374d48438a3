"""Racing line: pay the car for driving on the fastest
line round the track, at that line's speed.

What it teaches: where to be and how fast. RACING_LINE
holds the limit lap's line of the model's track (racer-tui
writes it in when the model is made; `racer-tui tracks
line TRACK --python` prints it for any track), each point
[x, y, speed to command]. A step pays more the nearer
the car is to the line (nothing half the road's width
away): a fifth of that for being there, the rest for
commanding the line's speed there (nothing 1 m/s away),
all in proportion to the speed, so that every metre of a
lap pays alike and a slow lap's extra steps do not pay
more. Off the road a step pays almost nothing.

Where it stops helping: the line keeps all four wheels on
the road; a car may cut further. Pasted into the DeepRacer
console with its line it runs unchanged.
"""

import math

RACING_LINE = []

# How far from the line a step still pays (a share of the
# track's width), and how far off the line's speed.
LINE_REACH = 0.5
SPEED_REACH = 1.0  # m/s
# What being on the line pays at any speed; the rest of a step's pay is for its speed.
ON_LINE_SHARE = 0.2
TOP_SPEED = 4.0  # m/s, the console's fastest action: a step pays at most 1
OFF_THE_ROAD = 0.001


def nearest_point(x, y):
    """The index of the line's point nearest (x, y)."""
    best, best_d2 = 0, math.inf
    for i, (px, py, _) in enumerate(RACING_LINE):
        d2 = (px - x) ** 2 + (py - y) ** 2
        if d2 < best_d2:
            best, best_d2 = i, d2
    return best


def distance_to_segment(x, y, a, b):
    """Metres from (x, y) to the segment from a to b."""
    ax, ay, bx, by = a[0], a[1], b[0], b[1]
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0
    if length2 > 0.0:
        t = ((x - ax) * dx + (y - ay) * dy) / length2
        t = min(1.0, max(0.0, t))
    return math.hypot(x - (ax + t * dx), y - (ay + t * dy))


def reward_function(params):
    if not RACING_LINE:
        raise ValueError(
            "RACING_LINE is empty: paste your track's line "
            "from `racer-tui tracks line TRACK --python`"
        )
    if params["is_offtrack"] or not params["all_wheels_on_track"]:
        return OFF_THE_ROAD
    x, y = params["x"], params["y"]
    i = nearest_point(x, y)
    before = RACING_LINE[i - 1]
    after = RACING_LINE[(i + 1) % len(RACING_LINE)]
    here = RACING_LINE[i]
    off_line = min(
        distance_to_segment(x, y, before, here),
        distance_to_segment(x, y, here, after),
    )
    reach = LINE_REACH * params["track_width"]
    on_line = max(0.0, 1.0 - off_line / reach)
    speed_gap = abs(params["speed"] - here[2])
    on_speed = max(0.0, 1.0 - speed_gap / SPEED_REACH)
    share = ON_LINE_SHARE + (1.0 - ON_LINE_SHARE) * on_speed
    pace = min(params["speed"], TOP_SPEED) / TOP_SPEED
    return float(OFF_THE_ROAD + on_line**2 * share * pace)

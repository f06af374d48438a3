"""Follow the centre line: the nearer the car drives to
it, the more each step pays.

What it teaches: keep to the middle of the road. Each
side of the centre line is cut into three bands, ending
at 10%, 25% and 50% of the track's width (the last one
is the edge of the road); the inner band pays 1.0, the
next 0.5, the outer one 0.1, and past the edge a step
pays almost nothing.

Where it stops helping: it pays a slow car as much as a
fast one, and it pays the middle of the road in corners
too, where a faster line cuts across. Once the car
finishes laps, pay for speed or progress as well.
"""

# Where each band ends (a fraction of the track's width,
# from the centre line) and what a step in it pays.
BANDS = ((0.10, 1.0), (0.25, 0.5), (0.50, 0.1))
PAST_THE_EDGE = 0.001


def reward_function(params):
    from_centre = params["distance_from_center"]
    width = params["track_width"]
    for band_end, pay in BANDS:
        if from_centre <= band_end * width:
            return float(pay)
    return PAST_THE_EDGE

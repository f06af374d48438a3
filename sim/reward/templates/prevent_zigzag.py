"""Follow the centre line without zig-zagging:
follow_center_line's pay, cut by a fifth on any step
that steers harder than 15 degrees either way.

What it teaches: drive straight where the road is
straight. A car paid only for the centre line often
weaves across it; making hard steering cost a little
smooths the path.

Where it stops helping: some corners need more than 15
degrees, and there the car is paid less for doing the
right thing. Set STEERING_LIMIT from your action space
(a little under its largest angle), and pay for speed
once laps complete.
"""

# Where each band ends (a fraction of the track's width,
# from the centre line) and what a step in it pays.
BANDS = ((0.10, 1.0), (0.25, 0.5), (0.50, 0.1))
PAST_THE_EDGE = 0.001
STEERING_LIMIT = 15.0  # degrees, either way
# What a step steering past the limit keeps of its pay.
HARD_STEERING_SHARE = 0.8


def centre_line_pay(params):
    from_centre = params["distance_from_center"]
    width = params["track_width"]
    for band_end, pay in BANDS:
        if from_centre <= band_end * width:
            return pay
    return PAST_THE_EDGE


def reward_function(params):
    pay = centre_line_pay(params)
    if abs(params["steering_angle"]) > STEERING_LIMIT:
        pay *= HARD_STEERING_SHARE
    return float(pay)

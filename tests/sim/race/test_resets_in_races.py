"""A race puts an off-track car back where DeepRacer's simulator puts it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.sim.race.drivers import ScriptedDriver


def test_an_offtrack_car_goes_back_on_the_lane_it_left_by() -> None:
    track = resolve_track("hairpin-circuit")
    driver = ScriptedDriver(track, swerve_at=(150,))  # turns hard right: leaves on the right
    result = run_race(track, RaceRules(window_seconds=30.0), driver)
    trace = result.trace
    assert trace is not None
    off = trace.statuses().index("off_track")
    x, y = float(trace.x[off + 1]), float(trace.y[off + 1])  # held where it was put back
    heading = math.radians(float(trace.heading[off + 1]))
    assert bool(trace.all_wheels_on[off + 1])
    centre = track.centerline
    seg, _, foot = centre.project(np.array([[x, y]]))
    tangent = centre.vectors[seg[0]] / centre.lengths[seg[0]]
    offset = np.array([x, y]) - foot[0]
    # On the right-hand lane, half-way between the centre line and the border...
    assert tangent[0] * offset[1] - tangent[1] * offset[0] < 0.0
    row = int(seg[0])
    width = float(track.widths[row])
    assert float(np.hypot(*offset)) == pytest.approx(width / 4.0, abs=0.02)
    # ...pointing along the track.
    along = math.atan2(tangent[1], tangent[0])
    assert abs(math.remainder(heading - along, 2 * math.pi)) < math.radians(15.0)

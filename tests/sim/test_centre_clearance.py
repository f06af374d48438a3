"""`Track.centre_clearance` lets a race skip its wheels' polygon tests, so it must never
claim a point is on the road that the polygon test would put off it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from sim.physics.simulation import TrackSimulation
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

TRACKS = ["reinvent_base", "hairpin-circuit", "bowtie-chicane", "2022_reinvent_champ_ccw"]


@pytest.mark.parametrize("name", TRACKS)
def test_points_within_a_segments_clearance_are_on_the_road(name: str) -> None:
    track = resolve_track(name)
    clearance = track.centre_clearance
    centre = track.centerline
    assert len(clearance) == len(centre.lengths)
    assert (clearance > 0).all()  # a validated track's centre line keeps to its road
    rng = np.random.default_rng(7)
    along = rng.uniform(0.0, 1.0, (20, len(clearance)))
    angle = rng.uniform(-math.pi, math.pi, along.shape)
    reach = rng.uniform(0.0, 1.0, along.shape) ** 0.25 * clearance * (1 - 1e-9)
    x = centre.starts[:, 0] + centre.vectors[:, 0] * along + reach * np.cos(angle)
    y = centre.starts[:, 1] + centre.vectors[:, 1] * along + reach * np.sin(angle)
    assert shapely.contains_xy(track.road, x.ravel(), y.ravel()).all()


@pytest.mark.parametrize("name", TRACKS)
def test_a_clearance_is_the_distance_to_the_nearest_edge(name: str) -> None:
    track = resolve_track(name)
    centre = track.centerline
    ends = np.stack([centre.starts, centre.starts + centre.vectors], axis=1)
    distance = shapely.distance(shapely.linestrings(ends), track.road.boundary)
    assert track.centre_clearance == pytest.approx(distance, abs=1e-12)


def test_a_centre_line_off_its_road_has_no_clearance_there() -> None:
    """Built without validation: a centre row pushed outside the outer border."""
    points = resolve_track("reinvent_base").points.copy()
    outward = points[10, 4:6] - points[10, 0:2]
    points[10, 0:2] = points[10, 4:6] + outward * 0.5
    track = Track(name="stray", points=points)
    clearance = track.centre_clearance
    assert clearance[9] == 0.0 and clearance[10] == 0.0
    assert (np.delete(clearance, [9, 10]) > 0).all()


def test_a_car_astride_the_edge_is_still_tested_wheel_by_wheel() -> None:
    """The fast path gives way to the polygon test near an edge: a car whose outer wheels
    are over the border has them off."""
    track = resolve_track("reinvent_base")
    sim = TrackSimulation(track, 1)
    (cx, cy), (ox, oy) = track.center[5], track.outer[5]
    heading = math.atan2(*(track.center[6] - track.center[5])[::-1])
    gap = math.hypot(ox - cx, oy - cy)
    # The car's centre 3 cm inside the border: its wheels 8 cm to either side of it.
    x, y = cx + (ox - cx) * (gap - 0.03) / gap, cy + (oy - cy) * (gap - 0.03) / gap
    sim.fleet.place(0, x, y, heading)
    sim._measure()
    assert sim.wheels_on[0].sum() == 2
    sim.fleet.place(0, float(cx), float(cy), heading)
    sim._measure()
    assert sim.wheels_on[0].all()

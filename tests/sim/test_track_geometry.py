"""The lookup grids of a track's lines: built once for the same points in a process, shared
read-only, and bounded."""

from __future__ import annotations

import numpy as np

from sim.tracks import geometry
from sim.tracks.catalog import resolve_track
from sim.tracks.geometry import PointProjector, PolylineProjector
from tests.sim.shapes import ring_track


def test_a_track_loaded_again_shares_the_grid_built_for_its_line() -> None:
    first = PointProjector.of(resolve_track("hairpin-circuit").centerline)
    again_track = resolve_track("hairpin-circuit")  # a new Track: a new projector
    again = PointProjector.of(again_track.centerline)
    assert again is not first
    assert again._grid is first._grid  # the same array, not another build
    assert again._grid is not None and not again._grid.flags.writeable
    # The kept grid is the grid these points build.
    assert np.array_equal(again._grid, again_track.centerline._lookup._build())
    x, y = (float(v) for v in again_track.center[7] + 0.05)
    assert again.project(x, y) == first.project(x, y)


def test_a_lazy_projector_takes_a_kept_grid_at_once_and_one_never_built_waits() -> None:
    track = resolve_track("beginner-oval")
    PointProjector.of(track.inner_border)  # builds the inner border's grid
    again = resolve_track("beginner-oval")
    assert again.inner_border._lookup.due(1) is not None  # kept: no reason to wait
    # A line whose grid was never built waits for enough queries, as before.
    fresh = PolylineProjector(ring_track(radius=3.3).center)
    assert fresh._lookup.due(1) is None


def test_the_process_keeps_a_bounded_number_of_grids_least_recently_used_first() -> None:
    lines = [PolylineProjector(ring_track(radius=2.0 + 0.1 * n).center) for n in range(20)]
    first = lines[0]._lookup.built()
    for line in lines[1:]:
        line._lookup.built()
    assert len(geometry._built_grids) == geometry._GRIDS_KEPT
    assert lines[0]._lookup._key not in geometry._built_grids
    assert lines[-1]._lookup._key in geometry._built_grids
    # Its projector keeps a grid the cache let go; a new projector builds an equal one.
    again = PolylineProjector(ring_track(radius=2.0).center)._lookup.built()
    assert again is not first and np.array_equal(again, first)

"""The fastest lap any car could drive on a track: a floor no honest lap time is under.

Until the coach computes each track's limit lap, the floor is the shortest loop a car can
drive round the track's infield (the perimeter of the infield's convex hull: any closed
path around it is at least that long) at DeepRacer's top speed (4 m/s, no car of either
kind goes faster). It is generous, so a fast honest lap is never refused, and it still
catches a forged "3.000 s" on a 17.8 m track.
"""

from __future__ import annotations

from functools import lru_cache

from shapely.geometry import Polygon

from sim.action_space import MAX_SPEED
from sim.track import Track


def shortest_loop_metres(track: Track) -> float:
    """The perimeter of the convex hull of the smaller of the two borders (the infield)."""
    borders = [Polygon(track.inner), Polygon(track.outer)]
    infield = min(borders, key=lambda polygon: polygon.area)
    return float(infield.convex_hull.length)


def fastest_possible_lap(track: Track) -> float:
    """Seconds: no lap on `track` can be quicker than this."""
    return shortest_loop_metres(track) / MAX_SPEED


@lru_cache(maxsize=64)
def fastest_possible_lap_by_hash(track_hash: str) -> float | None:
    """The floor for a track this machine knows by its content hash, else None."""
    from sim.track import TrackError, load_track
    from sim.track_catalog import find_track_by_hash

    info = find_track_by_hash(track_hash)
    if info is None or not info.lappable:
        return None
    try:
        return fastest_possible_lap(load_track(info.path, info.name))
    except TrackError:
        return None

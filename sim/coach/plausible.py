"""The fastest lap any car could drive on a track: a floor no honest lap time is under.

One floor for every place a lap enters a league (submit, a race recorded, a record pulled,
a night's heats), by the track's content hash (`fastest_possible_lap_by_hash`):

- Laps of a simulator (racer-tui's physics or DeepRacer's): the limit lap of a car more
  able than any DeepRacer car, under DeepRacer's rules (the road widened by what a car
  may cut, 4 m/s), `sim.coach.lap_floor`. Where the solver finds no line for a track at
  all, the hull floor below.
- Laps of a physical car, timed by hand or by a timer on a real track: the shortest loop
  round the track's infield (the perimeter of the infield's convex hull: any closed path
  around it is at least that long) at `PHYSICAL_TOP_SPEED`.
- A track this machine does not have: no floor can be said (None).

The hull floor is the shortest loop at DeepRacer's top speed (4 m/s): generous, so a fast
honest lap is never refused (a car cutting the infield by what it may, 0.115 m, saves at
most 0.7 m of that loop, far less than its corners cost it), and it still catches a
forged "3.000 s" on a 17.8 m track.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Final

from shapely.geometry import Polygon

from sim.deepracer.vocabulary import MAX_SPEED
from sim.physics.labels import PHYSICAL
from sim.tracks.catalog import find_track_by_hash
from sim.tracks.track import Track, TrackError, load_track

# A real DeepRacer car's top speed, for the floor of physical laps. Its action space tops
# at 4 m/s, but a host calibrates the real car's throttle by hand, and nobody publishes
# what its motor does flat out: 6 m/s is half as fast again. A hand-timed lap can also be
# mistimed, so this floor is deliberately far below any real lap: on re:Invent 2018 it is
# 2.5 s, where the physical world record of 2019 was 7.8 s; a lap under it is no late
# press but a lap that was not driven.
PHYSICAL_TOP_SPEED: Final = 6.0


def shortest_loop_metres(track: Track) -> float:
    """The perimeter of the convex hull of the smaller of the two borders (the infield)."""
    borders = [Polygon(track.inner), Polygon(track.outer)]
    infield = min(borders, key=lambda polygon: polygon.area)
    return float(infield.convex_hull.length)


def hull_floor(track: Track, top_speed: float = MAX_SPEED) -> float:
    """Seconds: the shortest loop at `top_speed` (module docstring)."""
    return shortest_loop_metres(track) / top_speed


def fastest_possible_lap(track: Track, physics: str = "") -> float:
    """Seconds: no lap of `physics` (`sim.physics.labels`) on `track` can be quicker."""
    if physics == PHYSICAL:
        return hull_floor(track, PHYSICAL_TOP_SPEED)
    from sim.coach.lap_floor import lap_floor  # noqa: PLC0415 (scipy: only for a simulated floor)

    floor = lap_floor(track)
    return hull_floor(track) if floor is None else floor


# Tracks found by their content hash (a content hash names one geometry for good); a hash
# not found is looked up again next time: the track may be imported meanwhile.
_tracks: dict[str, Track] = {}


def _track_by_hash(track_hash: str) -> Track | None:

    if track_hash in _tracks:
        return _tracks[track_hash]
    info = find_track_by_hash(track_hash)
    if info is None or not info.lappable:
        return None
    try:
        track = load_track(info.path, info.name)
    except TrackError:
        return None
    _tracks[track_hash] = track
    return track


def fastest_possible_lap_by_hash(track_hash: str, physics: str = "") -> float | None:
    """The floor for a track this machine knows by its content hash, else None."""
    track = _track_by_hash(track_hash)
    return None if track is None else fastest_possible_lap(track, physics)


@dataclass(frozen=True)
class ImpossibleLap:
    """A lap quicker than its track's floor."""

    number: int
    seconds: float
    floor: float
    physical: bool

    @property
    def why(self) -> str:
        """Where the floor comes from, for people."""
        if self.physical:
            return f"its shortest loop at {PHYSICAL_TOP_SPEED:g} m/s, a real car's top speed"
        return "under DeepRacer's rules at 4 m/s"

    def sentence(self, track: str) -> str:
        """ "lap 1 of 3.900 s is faster than any DeepRacer car can drive reinvent_base (no
        lap under 4.140 s is possible there: under DeepRacer's rules at 4 m/s)"."""
        who = "a real car" if self.physical else "any DeepRacer car"
        return (
            f"lap {self.number} of {self.seconds:.3f} s is faster than {who} can drive {track} "
            f"(no lap under {self.floor:.3f} s is possible there: {self.why})"
        )


def first_impossible_lap(
    track_hash: str, physics: str, laps: Iterable[tuple[int, float]]
) -> ImpossibleLap | None:
    """The first of `laps` (number, seconds: as driven, or with penalties, which only add)
    quicker than the track's floor for `physics`; None when none is, or the track is not
    known here."""
    laps = list(laps)
    if not laps:
        return None
    floor = fastest_possible_lap_by_hash(track_hash, physics)
    if floor is None:
        return None
    for number, seconds in laps:
        if seconds < floor:
            return ImpossibleLap(number, seconds, floor, physics == PHYSICAL)
    return None

"""DeepRacer on AWS's tracks: its track ids, the directions it allows on each, and the file
each id and direction means.

DeepRacer on AWS (DRoA, the console's successor) lists 62 tracks
(`source/libs/config/src/data/tracks.json` in aws-solutions/deepracer-on-aws), copied in
`tracks/official/droa_tracks.csv`: the id, the enum name its API uses, the name racers
see, the directions it allows and the one it proposes. A model's `training_params.yaml`
says the track as DRoA's id alone (`WORLD_NAME: 2022_april_open`) and, on a track with
two directions, the direction as `TRACK_DIRECTION_CLOCKWISE: true|false`; DRoA's own
import reads only the YAML boolean `true` as clockwise. The simulator's track file is
`<id>_cw` or `<id>_ccw` on a two-direction track and `<id>` on a one-direction track (the
route files DRoA's reward validator loads); every one of them is an official track here.
"""

from __future__ import annotations

import csv
import functools
import io
from dataclasses import dataclass

from sim.deepracer.files import TrainingParams
from sim.tracks.errors import TrackError
from sim.tracks.official import official_dir

DROA_CATALOG_FILE = "droa_tracks.csv"
DROA_DIRECTION_KEY = "TRACK_DIRECTION_CLOCKWISE"  # in DRoA's training_params.yaml
CLOCKWISE = "clockwise"
COUNTER_CLOCKWISE = "counter-clockwise"
# DRoA's words for the directions, as its API and its error sentences write them.
DROA_DIRECTION = {CLOCKWISE: "CLOCKWISE", COUNTER_CLOCKWISE: "COUNTER_CLOCKWISE"}


@dataclass(frozen=True)
class DroaTrack:
    track_id: str  # DRoA's trackId: WORLD_NAME in its training_params.yaml
    enum_name: str  # its API's TrackId, e.g. ACE_SPEEDWAY
    name: str  # what racers see, e.g. "Ace Speedway"
    directions: tuple[str, ...]  # the directions DRoA allows here
    default_direction: str

    def world_name(self, direction: str) -> str:
        """The simulator's track file (its stem) for `direction`; `DroaDirectionError`
        where DRoA does not allow that direction on this track."""
        if direction not in self.directions:
            raise DroaDirectionError(self.track_id, direction)
        if len(self.directions) == 1:
            return self.track_id
        return f"{self.track_id}_{'cw' if direction == CLOCKWISE else 'ccw'}"


class DroaDirectionError(TrackError):
    """A direction DRoA refuses on a track; the message is DRoA's own sentence."""

    def __init__(self, track_id: str, direction: str) -> None:
        self.track_id = track_id
        self.direction = direction
        super().__init__(
            "Invalid track configuration. Track "
            f"{track_id} is not available in direction {DROA_DIRECTION[direction]}."
        )


def droa_direction_sentence(error: DroaDirectionError) -> str:
    """DRoA's refusal, and what to do about it."""
    return (
        f"{error} (DeepRacer on AWS's rule, in training_params.yaml); set "
        f"{DROA_DIRECTION_KEY} to a direction the track allows, or give the track with "
        "--track."
    )


@functools.cache
def droa_tracks() -> dict[str, DroaTrack]:
    """DRoA's tracks by id, in DRoA's order."""
    path = official_dir() / DROA_CATALOG_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TrackError(f"{path}: cannot be read ({exc.strerror}); reinstall racer-tui.") from None
    found: dict[str, DroaTrack] = {}
    for row in csv.DictReader(io.StringIO(text)):
        directions = tuple(row["directions"].split())
        found[row["track_id"]] = DroaTrack(
            track_id=row["track_id"],
            enum_name=row["track_enum"],
            name=row["name"],
            directions=directions,
            default_direction=row["default_direction"],
        )
    return found


def droa_world_name(track_id: str, clockwise: object) -> str | None:
    """The track file DRoA means by `WORLD_NAME: track_id` with `TRACK_DIRECTION_CLOCKWISE:
    clockwise` (None: the key is absent), read as DRoA's import reads it; None when
    `track_id` is not one of DRoA's. A one-direction track ignores an absent key; a
    direction it does not allow raises `DroaDirectionError`, as DRoA refuses it."""
    track = droa_tracks().get(track_id)
    if track is None:
        return None
    if clockwise is None:
        if len(track.directions) == 1:
            return track.world_name(track.default_direction)
        clockwise = False  # DRoA: anything but the boolean true is counter-clockwise
    direction = CLOCKWISE if clockwise is True else COUNTER_CLOCKWISE
    return track.world_name(direction)


def training_world(params: TrainingParams) -> str:
    """The track file a `training_params.yaml` means: DRoA's track id and direction key
    where the file has that key (DroaDirectionError where DRoA would refuse them), else
    WORLD_NAME as DeepRacer's simulator and deepracer-for-cloud name the file."""
    if DROA_DIRECTION_KEY in params.extra:
        found = droa_world_name(params.world_name, params.extra[DROA_DIRECTION_KEY])
        if found is not None:
            return found
    return params.world_name

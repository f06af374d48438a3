"""AWS DeepRacer's official tracks, shipped in `tracks/official/` with their catalog.

The 127 `.npy` files are the DeepRacer simulator's own track files (Apache-2.0, licence
beside them). `catalog.csv` names each one the way racers know it: the simulator's world
name (`reinvent_base`, the file's stem), the console's name (`re:Invent 2018`) and track id,
and the release date; the facts (length, width, direction, waypoints, content hash) are
computed from the files by `rebuild_catalog`, with the same arithmetic as `sim.tracks.track`, so
listing shows exactly what loading the track gives without loading a single array.

Reading the catalog uses only the standard library: `racer-tui tracks list` stays fast.
"""

from __future__ import annotations

import csv
import functools
import io
from dataclasses import dataclass
from pathlib import Path

import tracks
from sim.tracks.errors import TrackError

OFFICIAL_DIR = "official"
CATALOG_FILE = "catalog.csv"
LICENSE_FILE = "LICENSE-deepracer-simapp.txt"
CATALOG_COLUMNS = (
    "world_name",
    "console_name",
    "console_track",
    "release_date",
    "length_m",
    "width_m",
    "direction",
    "waypoints",
    "closed",
    "sha256",
)


@dataclass(frozen=True)
class OfficialTrack:
    """One row of the official catalog."""

    world_name: str  # the simulator's WORLD_NAME and the file's stem
    console_name: str  # "re:Invent 2018"; empty for files the console never listed
    console_track: str  # the console's track id; direction variants share it
    release_date: str  # YYYY-MM-DD, or empty when the console never listed it
    length_m: float
    width_m: float
    direction: str  # "counter-clockwise", "clockwise", or "straight" for the one non-loop
    waypoints: int
    closed: bool  # False only for Straight_track, which cannot be lapped
    sha256: str  # Track.content_hash of the loaded file; empty when it is not a loop

    @property
    def path(self) -> Path:
        return official_dir() / f"{self.world_name}.npy"

    @property
    def release_year(self) -> str:
        return self.release_date[:4]


def official_dir() -> Path:
    return Path(tracks.__file__).parent / OFFICIAL_DIR


@functools.cache
def official_tracks() -> tuple[OfficialTrack, ...]:
    """Every official track, in catalog order (by world name)."""
    path = official_dir() / CATALOG_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TrackError(f"{path}: cannot be read ({exc.strerror}); reinstall racer-tui.") from None
    return tuple(_row(row, path) for row in csv.DictReader(io.StringIO(text)))


def _row(row: dict[str, str], path: Path) -> OfficialTrack:
    try:
        return OfficialTrack(
            world_name=row["world_name"],
            console_name=row["console_name"],
            console_track=row["console_track"],
            release_date=row["release_date"],
            length_m=float(row["length_m"]),
            width_m=float(row["width_m"]),
            direction=row["direction"],
            waypoints=int(row["waypoints"]),
            closed=row["closed"] == "true",
            sha256=row["sha256"],
        )
    except (KeyError, ValueError, TypeError):
        raise TrackError(
            f"{path}: the row for {row.get('world_name')!r} is damaged; reinstall racer-tui."
        ) from None


def rebuild_catalog(source_catalog: Path, directory: Path | None = None) -> str:
    """The catalog text for the files in `directory`: names and dates from `source_catalog`
    (the shared DeepRacer catalog), every fact recomputed here from the file itself."""
    import numpy as np  # noqa: PLC0415 (only when the catalog is rebuilt)

    from sim.tracks.track import load_track  # noqa: PLC0415 (only when the catalog is rebuilt)

    folder = directory or official_dir()
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CATALOG_COLUMNS)
    rows = csv.DictReader(io.StringIO(source_catalog.read_text(encoding="utf-8")))
    for row in sorted(rows, key=lambda r: r["world_name"]):
        npy = folder / f"{row['world_name']}.npy"
        names = [row["world_name"], row["console_name"], row["console_track"]]
        names.append(row["release_date"])
        if row["closed"] == "true":
            track = load_track(npy)
            facts = track.summary()
            writer.writerow(
                [
                    *names,
                    f"{facts['length_m']:.2f}",
                    f"{facts['width_m']:.3f}",
                    facts["direction"],
                    facts["waypoints"],
                    "true",
                    track.content_hash,
                ]
            )
            continue
        # Not a loop (Straight_track): the facts of the raw centre line, and no identity,
        # since no track is ever built from it.
        points = np.load(npy, allow_pickle=False)
        length = float(np.hypot(*np.diff(points[:, 0:2], axis=0).T).sum())
        width = float(np.mean(np.hypot(*(points[:, 4:6] - points[:, 2:4]).T)))
        writer.writerow(
            [*names, f"{length:.2f}", f"{width:.3f}", "straight", len(points), "false", ""]
        )
    return out.getvalue()


if __name__ == "__main__":
    import sys

    # Maintainers: python -m sim.tracks.official ../shared/deepracer/tracks/catalog.csv
    if len(sys.argv) != 2:
        raise SystemExit("usage: python -m sim.tracks.official SOURCE_CATALOG.csv")
    text = rebuild_catalog(Path(sys.argv[1]))
    (official_dir() / CATALOG_FILE).write_text(text, encoding="utf-8")

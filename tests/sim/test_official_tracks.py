"""AWS DeepRacer's official tracks ship with racer-tui: every file, its catalog and licence,
and every loop is lapped cleanly by the reference driver."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from sim.physics.car import DEEPRACER_CAR
from sim.physics.reference_driver import reference_lap
from sim.tracks.catalog import resolve_track
from sim.tracks.official import (
    CATALOG_FILE,
    LICENSE_FILE,
    official_dir,
    official_tracks,
    rebuild_catalog,
)
from sim.tracks.track import load_track

LOOPS = [track.world_name for track in official_tracks() if track.closed]


def test_all_127_files_ship_with_the_apache_licence() -> None:
    files = sorted(official_dir().glob("*.npy"))

    assert len(files) == 127
    assert [path.stem for path in files] == sorted(t.world_name for t in official_tracks())
    assert "Apache License" in (official_dir() / LICENSE_FILE).read_text(encoding="utf-8")


def test_shipped_files_are_deepracers_own(deepracer_dir: Path) -> None:
    for track in official_tracks():
        shipped = track.path.read_bytes()
        assert shipped == (deepracer_dir / "tracks" / f"{track.world_name}.npy").read_bytes()


def test_catalog_facts_are_what_the_files_give(deepracer_dir: Path) -> None:
    """Names and dates from DeepRacer's catalog, facts and identities recomputed from the files."""
    source = deepracer_dir / "tracks" / CATALOG_FILE

    rebuilt = rebuild_catalog(source)

    assert rebuilt == (official_dir() / CATALOG_FILE).read_text(encoding="utf-8")


def test_listing_facts_match_the_loaded_track() -> None:
    for entry in official_tracks():
        if not entry.closed:
            continue
        track = load_track(entry.path)
        assert entry.sha256 == track.content_hash, entry.world_name
        assert entry.length_m == round(track.length, 2), entry.world_name
        assert entry.direction == track.direction, entry.world_name


def test_only_the_straight_test_road_is_not_a_loop() -> None:
    assert [t.world_name for t in official_tracks() if not t.closed] == ["Straight_track"]


@pytest.mark.parametrize("world", LOOPS)
def test_reference_driver_laps_every_official_track(world: str) -> None:
    track = resolve_track(world)

    lap = reference_lap(track)

    assert lap.status == "Lap complete", f"{world}: {lap.status}"
    assert not math.isnan(lap.lap_time)
    assert 1.0 < track.length / lap.lap_time < DEEPRACER_CAR.max_speed

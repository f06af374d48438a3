"""The built-in tracks and the builder that makes them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from shapely.geometry import LinearRing, Polygon

from sim.tracks.builder import (
    Arc,
    Segment,
    Straight,
    TrackDesignError,
    build_from_control_points,
    build_from_segments,
    close_loop,
)
from sim.tracks.catalog import builtin_dir, resolve_track
from sim.tracks.designs import DESIGNS, write_builtin_tracks
from sim.tracks.track import Track, TrackError

WIDTHS = (0.76, 1.07)
EXPECTED = {
    # name: (min length, max length, width)
    "beginner-oval": (15.0, 30.0, 1.07),
    "hairpin-circuit": (17.0, 18.0, 0.76),
    "bowtie-chicane": (15.0, 22.0, 0.76),
    "speedway": (22.0, 24.0, 1.07),
    "grand-prix": (55.0, 65.0, None),
}


def turn_radii(centre: np.ndarray) -> np.ndarray:
    """Radius of the circle through each waypoint and its two neighbours (closed loop)."""
    ring = centre[:-1]
    before, after = np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0)
    a = np.hypot(*(ring - before).T)
    b = np.hypot(*(after - ring).T)
    c = np.hypot(*(after - before).T)
    cross = (ring - before)[:, 0] * (after - before)[:, 1] - (ring - before)[:, 1] * (
        after - before
    )[:, 0]
    with np.errstate(divide="ignore"):
        return np.asarray(a * b * c / (2 * np.abs(cross)))


def smoothed(values: np.ndarray) -> np.ndarray:
    """Median of each value and its neighbours: one odd triple cannot fake a hairpin."""
    stacked = np.stack([np.roll(values, 1), values, np.roll(values, -1)])
    return np.asarray(np.median(stacked, axis=0))


def hairpins(track: Track, max_radius: float) -> list[tuple[float, float]]:
    """(smallest radius, degrees turned) of each run of waypoints tighter than `max_radius`."""
    radii = smoothed(turn_radii(track.center))
    tight = radii < max_radius
    headings = np.unwrap(np.arctan2(*np.diff(track.center, axis=0).T[::-1]))
    # Heading change at each waypoint: between the segments before and after it.
    turn = np.roll(np.diff(np.concatenate([headings, headings[:1] + 2 * math.pi])), 1)
    found = []
    start = int(np.argmin(tight))  # begin outside a run so none is split across the seam
    run: list[int] = []
    for i in [*range(start, len(tight)), *range(start)]:
        if tight[i]:
            run.append(i)
        elif run:
            found.append((float(radii[run].min()), math.degrees(abs(turn[run].sum()))))
            run = []
    return found


@pytest.fixture(scope="module")
def builtin() -> dict[str, Track]:
    return {name: resolve_track(name) for name in EXPECTED}


def test_the_five_builtin_tracks_exist_and_validate(builtin: dict[str, Track]) -> None:
    assert [design.name for design in DESIGNS] == list(EXPECTED)
    for name, track in builtin.items():
        assert track.name == name
        assert track.description.endswith(".")
        again = Track.from_array(track.points, name)  # validates once more from the raw rows
        assert again.content_hash == track.content_hash


@pytest.mark.parametrize("name", list(EXPECTED))
def test_lengths_widths_and_direction(builtin: dict[str, Track], name: str) -> None:
    low, high, width = EXPECTED[name]
    track = builtin[name]

    assert low <= track.length <= high
    assert any(track.width == pytest.approx(w, abs=0.001) for w in ([width] if width else WIDTHS))
    assert np.allclose(track.widths, track.width, atol=1e-5)
    assert track.direction == "counter-clockwise"
    assert np.array_equal(track.points[0], track.points[-1])


@pytest.mark.parametrize("name", list(EXPECTED))
def test_tracks_sit_in_a_box_near_the_origin(builtin: dict[str, Track], name: str) -> None:
    min_x, min_y, max_x, max_y = builtin[name].bounds

    assert 0.0 < min_x < 1.0 and 0.0 < min_y < 1.0
    assert max_x < 25.0 and max_y < 15.0


@pytest.mark.parametrize("name", list(EXPECTED))
def test_waypoints_are_about_as_far_apart_as_deepracer_s(
    builtin: dict[str, Track], name: str
) -> None:
    steps = np.hypot(*np.diff(builtin[name].center, axis=0).T)

    assert steps.min() > 0.12 and steps.max() < 0.16


def test_technical_circuit_has_two_hairpins_of_055_m(builtin: dict[str, Track]) -> None:
    track = builtin["hairpin-circuit"]

    found = hairpins(track, max_radius=0.57)

    assert len(found) == 2
    for radius, degrees in found:
        assert radius == pytest.approx(0.55, abs=0.02)
        assert degrees > 135  # a U-turn; the run edges miss a few degrees of the 180
    assert smoothed(turn_radii(track.center)).min() == pytest.approx(0.55, abs=0.02)


def test_bowtie_pinches_at_a_waist_without_crossing_itself(builtin: dict[str, Track]) -> None:
    centre = builtin["bowtie-chicane"].center

    assert LinearRing(centre).is_simple
    outline = Polygon(centre)
    # A bowtie is far from convex: its waist bites deep into the hull.
    assert outline.area / outline.convex_hull.area < 0.85


def test_index_yaml_matches_the_arrays(builtin: dict[str, Track]) -> None:
    entries = yaml.safe_load((builtin_dir() / "index.yaml").read_text(encoding="utf-8"))

    assert [entry["name"] for entry in entries] == list(EXPECTED)
    for entry in entries:
        track = builtin[entry["name"]]
        assert entry["file"] == f"{entry['name']}.npy"
        assert entry["description"] == track.description
        assert entry["length_m"] == round(track.length, 2)
        assert entry["width_m"] == round(track.width, 3)
        assert entry["direction"] == track.direction
        assert entry["waypoints"] == len(track.points)
        assert entry["sha256"] == track.content_hash


def test_rerunning_the_designs_rewrites_identical_files(tmp_path: Path) -> None:
    write_builtin_tracks(tmp_path)

    shipped = sorted(p.name for p in builtin_dir().iterdir() if p.suffix in (".npy", ".yaml"))
    assert sorted(p.name for p in tmp_path.iterdir()) == shipped
    for name in shipped:
        assert (tmp_path / name).read_bytes() == (builtin_dir() / name).read_bytes(), name


# --- the builder ----------------------------------------------------------------------------


def test_free_straights_close_the_loop() -> None:
    pieces = close_loop([Straight(), Arc(1.8, 190), Straight(), Arc(1.3, 170)])

    free = [piece.length for piece in pieces if isinstance(piece, Straight)]
    assert len(free) == 2 and all(length is not None and length > 0 for length in free)
    track = build_from_segments("egg", pieces, width=1.07)
    assert np.array_equal(track.points[0], track.points[-1])


def test_a_turn_too_tight_for_the_road_is_refused() -> None:
    design: list[Segment] = [Straight(3.0), Arc(0.3, 180), Straight(3.0), Arc(0.3, 180)]

    with pytest.raises(TrackDesignError, match=r"0\.300 m radius.*at least 0\.430 m"):
        build_from_segments("tight", design, width=0.76)


def test_turns_must_add_up_to_one_loop() -> None:
    with pytest.raises(TrackDesignError, match="360"):
        close_loop([Straight(), Arc(1.0, 180), Straight(), Arc(1.0, 90)])


def test_a_clockwise_design_is_refused() -> None:
    design: list[Segment] = [Straight(3.0), Arc(1.0, -180), Straight(3.0), Arc(1.0, -180)]

    with pytest.raises(TrackDesignError, match="clockwise"):
        build_from_segments("backwards", design, width=0.76)


def pocketed_box(depth: float) -> list[Segment]:
    """A 4 m tall loop with a dip from the bottom edge whose hairpin reaches towards the top."""
    pocket: list[Segment] = [
        Arc(0.6, 90),
        Straight(depth),
        Arc(0.55, -180),
        Straight(depth),
        Arc(0.6, 90),
    ]
    right_end: list[Segment] = [Arc(1.5, 90), Straight(1.0), Arc(1.5, 90)]
    left_end: list[Segment] = [Arc(1.5, 90), Straight(), Arc(1.5, 90)]
    return [Straight(), *pocket, Straight(1.0), *right_end, Straight(5.0), *left_end]


def test_road_that_comes_back_too_close_is_refused() -> None:
    # The hairpin's road edge ends 2.09 - depth from the top road: 0.05 m here, under 0.3 m
    # (the check measures at waypoints, so it may report a few centimetres more).
    with pytest.raises(TrackError, match=r"within 0\.0\d m of itself"):
        build_from_segments("crowded", pocketed_box(2.04), width=0.76)

    roomy = build_from_segments("roomy", pocketed_box(1.7), width=0.76)
    assert roomy.direction == "counter-clockwise"


def test_control_point_tracks_are_valid_and_counter_clockwise() -> None:
    angles = np.linspace(0, 2 * math.pi, 8, endpoint=False)
    points = np.stack([4 * np.cos(angles), 2.5 * np.sin(angles)], axis=1)

    track = build_from_control_points("ellipse", points, width=1.07)

    assert track.direction == "counter-clockwise"
    assert track.width == pytest.approx(1.07, abs=1e-5)

"""The seeded track generator: every seed gives a valid track, the same one every time."""

from __future__ import annotations

import numpy as np
import pytest

from sim.tracks import generator as track_generator
from sim.tracks.generator import MAX_LENGTH, MIN_LENGTH, generate_track
from sim.tracks.track import Track, TrackError

SEEDS = range(50)


@pytest.fixture(scope="module")
def generated() -> dict[int, Track]:
    return {seed: generate_track(seed, width=1.07 if seed % 5 == 0 else 0.76) for seed in SEEDS}


def test_fifty_seeds_all_give_valid_tracks(generated: dict[int, Track]) -> None:
    for seed, track in generated.items():
        again = Track.from_array(track.points, track.name)  # full validation from the raw rows
        assert again.content_hash == track.content_hash
        assert track.name == f"generated-{seed}"
        assert track.direction == "counter-clockwise"
        assert MIN_LENGTH <= track.length <= MAX_LENGTH
        assert np.array_equal(track.points[0], track.points[-1])
        assert str(seed) in track.description


def test_widths_are_as_asked(generated: dict[int, Track]) -> None:
    for seed, track in generated.items():
        expected = 1.07 if seed % 5 == 0 else 0.76
        assert np.allclose(track.widths, expected, atol=1e-5), seed


def test_lengths_vary_across_seeds(generated: dict[int, Track]) -> None:
    lengths = [track.length for track in generated.values()]

    assert max(lengths) - min(lengths) > 10.0


@pytest.mark.parametrize("seed", [0, 7, 123456789])
def test_same_seed_gives_byte_identical_track(seed: int) -> None:
    first = generate_track(seed)
    second = generate_track(seed)

    assert first.to_npy_bytes() == second.to_npy_bytes()


def test_different_seeds_differ(generated: dict[int, Track]) -> None:
    hashes = {track.content_hash for track in generated.values()}

    assert len(hashes) == len(generated)


@pytest.mark.parametrize("length", [12.0, 25.0, 40.0])
def test_target_length_is_met(length: float) -> None:
    track = generate_track(3, target_length=length)

    # The waypoint polyline cuts the spline's corners by a hair.
    assert track.length == pytest.approx(length, rel=0.005)


def test_width_changes_the_road_not_the_seed_s_determinism() -> None:
    narrow, wide = generate_track(11, width=0.76), generate_track(11, width=1.07)

    assert narrow.width == pytest.approx(0.76, abs=1e-5)
    assert wide.width == pytest.approx(1.07, abs=1e-5)
    assert generate_track(11, width=1.07).content_hash == wide.content_hash


@pytest.mark.parametrize(
    ("seed", "width", "length", "problem"),
    [
        (-1, 0.76, None, "negative"),
        (1, 0.3, None, "width"),
        (1, 3.0, None, "width"),
        (1, 0.76, 5.0, "length"),
        (1, 0.76, 200.0, "length"),
    ],
)
def test_impossible_requests_are_refused(
    seed: int, width: float, length: float | None, problem: str
) -> None:
    with pytest.raises(TrackError, match=problem):
        generate_track(seed, width=width, target_length=length)


def test_when_every_random_shape_fails_a_stadium_still_comes_back(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(track_generator, "_MAX_ATTEMPTS", 0)

    track = generate_track(9, width=1.07, target_length=20.0)

    assert track.name == "generated-9"
    assert track.length == pytest.approx(20.0, rel=0.005)
    assert track.direction == "counter-clockwise"


@pytest.mark.parametrize(("width", "length"), [(0.4, 12.0), (1.5, 12.0), (1.5, 40.0), (0.4, 40.0)])
def test_extreme_requests_still_give_valid_tracks(width: float, length: float) -> None:
    for seed in range(5):
        track = generate_track(seed, width=width, target_length=length)
        assert track.width == pytest.approx(width, abs=1e-5)
        assert track.length == pytest.approx(length, rel=0.005)

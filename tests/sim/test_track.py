"""Loading DeepRacer track files: real ones load unchanged, bad ones fail in one clear sentence."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sim.tracks.track import Track, TrackError, load_track

REAL_TRACKS = {
    # file stem: (centre line length m, width m)
    "reinvent_base": (17.71, 0.762),
    "Oval_track": (19.55, 0.71),
    "Bowtie_track": (17.43, 0.79),
    "reInvent2019_wide": (16.64, 1.067),
}


def ring(n: int = 80, rx: float = 3.0, ry: float = 2.0, width: float = 0.76) -> np.ndarray:
    """A counter-clockwise ellipse track in DeepRacer's (N, 6) layout, closing row included."""
    t = np.linspace(0.0, 2 * math.pi, n + 1)
    centre = np.stack([4.0 + rx * np.cos(t), 3.0 + ry * np.sin(t)], axis=1)
    tangent = np.stack([-rx * np.sin(t), ry * np.cos(t)], axis=1)
    tangent /= np.hypot(*tangent.T)[:, None]
    left = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
    inner, outer = centre + left * width / 2, centre - left * width / 2
    rows = np.hstack([centre, inner, outer])
    rows[-1] = rows[0]
    return rows


def without_repeated_centres(raw: np.ndarray) -> np.ndarray:
    keep = np.ones(len(raw), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(raw[:, 0:2], axis=0)) > 1e-9, axis=1)
    return raw[keep]


# --- real DeepRacer files -----------------------------------------------------------------


@pytest.mark.parametrize("stem", sorted(REAL_TRACKS))
def test_real_deepracer_track_loads_unchanged(deepracer_dir: Path, stem: str) -> None:
    path = deepracer_dir / "tracks" / f"{stem}.npy"
    raw = np.load(path, allow_pickle=False)

    track = load_track(path)

    assert track.name == stem
    assert np.array_equal(track.points, without_repeated_centres(raw))
    assert np.array_equal(track.points[0], track.points[-1])


@pytest.mark.parametrize("stem", sorted(REAL_TRACKS))
def test_real_deepracer_track_facts(deepracer_dir: Path, stem: str) -> None:
    length, width = REAL_TRACKS[stem]

    track = load_track(deepracer_dir / "tracks" / f"{stem}.npy")

    assert track.length == pytest.approx(length, abs=0.01)
    assert track.width == pytest.approx(width, abs=0.01)
    assert track.direction == "counter-clockwise"


@pytest.mark.parametrize("stem", sorted(REAL_TRACKS))
def test_reverse_flips_direction_and_keeps_the_road(deepracer_dir: Path, stem: str) -> None:
    path = deepracer_dir / "tracks" / f"{stem}.npy"
    forward = load_track(path)

    backward = load_track(path, reverse=True)

    assert backward.direction == "clockwise"
    assert backward.length == pytest.approx(forward.length)
    assert np.array_equal(backward.inner, forward.inner[::-1])
    assert backward.road.equals(forward.road)


def test_a_valid_synthetic_ring_is_accepted() -> None:
    track = Track.from_array(ring(), "ring")

    assert track.direction == "counter-clockwise"
    assert track.width == pytest.approx(0.76)


# --- bad files ------------------------------------------------------------------------------


def save(path: Path, array: np.ndarray) -> Path:
    np.save(path, array, allow_pickle=False)
    return path


def load_error(path: Path) -> str:
    with pytest.raises(TrackError) as caught:
        load_track(path)
    message = str(caught.value)
    assert path.name in message
    return message


def test_wrong_shape(tmp_path: Path) -> None:
    message = load_error(save(tmp_path / "four_columns.npy", ring()[:, :4]))

    assert "shape" in message and "(N, 6)" in message


def test_nan(tmp_path: Path) -> None:
    array = ring()
    array[5, 3] = np.nan

    message = load_error(save(tmp_path / "has_nan.npy", array))

    assert "NaN" in message and "row 5" in message


def test_fewer_than_three_points(tmp_path: Path) -> None:
    message = load_error(save(tmp_path / "two_points.npy", ring()[[0, 20]]))

    assert "at least 3" in message


def test_self_intersecting_borders(tmp_path: Path) -> None:
    # Ends this sharp (radius 0.08 m) fold a 0.76 m road's inner border over itself.
    array = ring(n=200, rx=3.0, ry=0.5)

    message = load_error(save(tmp_path / "folded.npy", array))

    assert "cross" in message


def test_inner_and_outer_swapped(tmp_path: Path) -> None:
    array = ring()[:, [0, 1, 4, 5, 2, 3]]

    message = load_error(save(tmp_path / "swapped.npy", array))

    assert "swapped" in message


def test_zero_width(tmp_path: Path) -> None:
    array = ring()
    array[:, 2:4] = array[:, 0:2]
    array[:, 4:6] = array[:, 0:2]

    message = load_error(save(tmp_path / "no_width.npy", array))

    assert "0.000 m wide" in message


@pytest.mark.parametrize(
    ("array", "says"),
    [
        (ring() * 1000.0, "m wide"),  # a file in millimetres: the road is 760 m wide
        (ring(rx=300.0, ry=200.0), "the track spans"),  # a plausible road, 600 m across
    ],
)
def test_a_track_in_the_wrong_units_is_refused(
    tmp_path: Path, array: np.ndarray, says: str
) -> None:
    message = load_error(save(tmp_path / "units.npy", array))

    assert says in message and "are its units metres?" in message


def test_not_a_closed_loop(tmp_path: Path) -> None:
    message = load_error(save(tmp_path / "open.npy", ring()[:50]))

    assert "not a closed loop" in message


def test_text_file_is_not_a_track(tmp_path: Path) -> None:
    path = tmp_path / "notes.npy"
    path.write_text("x,y\n1,2\n", encoding="utf-8")

    message = load_error(path)

    assert "not a NumPy .npy" in message


class _Booby:
    """Unpickling this creates `marker`: proof that a loader ran code from the file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[object, tuple[str, str]]:
        return (open, (str(self.marker), "w"))


def test_pickled_object_array_is_refused_without_unpickling(tmp_path: Path) -> None:
    marker = tmp_path / "code-ran"
    path = tmp_path / "pickled.npy"
    np.save(path, np.array([_Booby(marker)], dtype=object), allow_pickle=True)
    # Prove the payload is live: a trusting loader would run it.
    np.load(path, allow_pickle=True)
    assert marker.exists()
    marker.unlink()

    message = load_error(path)

    assert "pickled" in message
    assert not marker.exists()


def test_missing_file(tmp_path: Path) -> None:
    message = load_error(tmp_path / "absent.npy")

    assert "no such file" in message


def resampled(track: Track, count: int) -> np.ndarray:
    """The track's six lines resampled to `count` waypoints (closing row included)."""
    points = track.points
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points[:, 0:2], axis=0).T))])
    at = np.linspace(0.0, along[-1], count)
    rows = np.stack([np.interp(at, along, points[:, k]) for k in range(6)], axis=1)
    rows[-1] = rows[0]
    return rows


def test_a_track_resampled_finely_loads_and_its_road_check_stays_exact(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from sim.tracks import track as track_module
    from sim.tracks.builder import build_from_segments
    from tests.sim.test_builtin_tracks import pocketed_box

    roomy = build_from_segments("roomy", pocketed_box(1.7), width=0.76)
    fine = load_track(save(tmp_path / "fine.npy", resampled(roomy, 4_900)))
    assert fine.length == pytest.approx(roomy.length, rel=1e-3)
    # The design whose hairpin comes back too close, built with the check switched off,
    # then resampled finely: the check still finds the close approach.
    with monkeypatch.context() as patch:
        patch.setattr(track_module, "_check_road_gaps", lambda points, label: None)
        crowded = build_from_segments("crowded", pocketed_box(2.04), width=0.76)
    with pytest.raises(TrackError, match=r"within 0\.0\d m of itself"):
        Track.from_array(resampled(crowded, 4_900), "dense")


def test_too_many_waypoints_or_too_big_a_file_is_one_sentence(tmp_path: Path) -> None:
    many = resampled(Track.from_array(ring(), "ring"), 60_000)
    message = load_error(save(tmp_path / "many.npy", many.astype(np.float32)))
    assert "has 60,000 waypoints; a track may have at most 5,000" in message
    huge = np.zeros((2_000_000, 6))
    message = load_error(save(tmp_path / "huge.npy", huge))
    assert "bytes; a track file is at most 2,000,000" in message

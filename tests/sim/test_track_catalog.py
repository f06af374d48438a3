"""Resolving track names: built-in tracks, a racer's imported tracks, and plain file paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sim.home import user_tracks_dir
from sim.track import TrackError, load_track
from sim.track_catalog import (
    TrackInfo,
    import_track,
    list_tracks,
    resolve_track,
    save_user_track,
)
from sim.track_generator import generate_track

BUILTIN = ["beginner-oval", "hairpin-circuit", "bowtie-chicane", "speedway", "grand-prix"]
REAL = ["Bowtie_track", "Oval_track", "reInvent2019_wide", "reinvent_base"]


def test_builtin_tracks_are_listed_first_with_their_facts() -> None:
    infos = list_tracks()

    assert [info.name for info in infos] == BUILTIN
    for info in infos:
        assert info.builtin
        assert info.path.is_file()
        assert info.description
        assert info.direction == "counter-clockwise"
        assert info.width_m in (0.76, 1.07)
        assert info.length_m == round(resolve_track(info.name).length, 2)


def test_resolve_builtin_by_name_carries_the_description() -> None:
    track = resolve_track("speedway")

    assert track.name == "speedway"
    assert track.description == list_tracks()[3].description


def test_unknown_name_lists_the_tracks_and_says_how_to_import() -> None:
    with pytest.raises(TrackError) as caught:
        resolve_track("monaco")

    message = str(caught.value)
    assert "'monaco'" in message
    assert all(name in message for name in BUILTIN)
    assert "tracks import" in message
    assert message.count(".") <= 2  # one sentence ("file." and the end)


def test_resolve_a_path_to_an_npy_file(deepracer_dir: Path) -> None:
    track = resolve_track(str(deepracer_dir / "tracks" / "Oval_track.npy"))

    assert track.name == "Oval_track"
    assert track.length == pytest.approx(19.55, abs=0.01)


def test_resolve_a_missing_path_says_so(tmp_path: Path) -> None:
    with pytest.raises(TrackError, match="no such file"):
        resolve_track(str(tmp_path / "nowhere.npy"))


@pytest.mark.parametrize("stem", REAL)
def test_import_real_track_then_resolve_it_by_name(deepracer_dir: Path, stem: str) -> None:
    source = deepracer_dir / "tracks" / f"{stem}.npy"

    info = import_track(source, description="From the AWS console.")

    assert info == TrackInfo(
        name=stem,
        description="From the AWS console.",
        length_m=round(load_track(source).length, 2),
        width_m=round(load_track(source).width, 3),
        direction="counter-clockwise",
        builtin=False,
        path=user_tracks_dir() / f"{stem}.npy",
    )
    resolved = resolve_track(stem)
    assert np.array_equal(resolved.points, load_track(source).points)
    assert resolved.description == "From the AWS console."
    assert [i.name for i in list_tracks()] == [*BUILTIN, stem]


def test_importing_twice_is_refused(deepracer_dir: Path) -> None:
    source = deepracer_dir / "tracks" / "reinvent_base.npy"
    import_track(source)

    with pytest.raises(TrackError, match=r"already imported.*--name"):
        import_track(source)
    with pytest.raises(TrackError, match="already imported"):
        import_track(source, "REINVENT_BASE")  # one file on case-insensitive disks

    again = import_track(source, "reinvent-copy")
    assert again.name == "reinvent-copy"


def test_import_reversed_runs_clockwise(deepracer_dir: Path) -> None:
    info = import_track(deepracer_dir / "tracks" / "Oval_track.npy", "oval-backwards", reverse=True)

    assert info.direction == "clockwise"
    assert resolve_track("oval-backwards").direction == "clockwise"


def test_a_builtin_name_cannot_be_taken(deepracer_dir: Path) -> None:
    with pytest.raises(TrackError, match=r"built-in track.*--name"):
        import_track(deepracer_dir / "tracks" / "Oval_track.npy", "speedway")


@pytest.mark.parametrize("name", ["has space", "dots.npy", "../escape", "", "x" * 65, "ünï"])
def test_bad_names_are_refused(deepracer_dir: Path, name: str) -> None:
    with pytest.raises(TrackError, match="letters, digits"):
        import_track(deepracer_dir / "tracks" / "Oval_track.npy", name)
    assert list(user_tracks_dir().iterdir()) == []


def test_a_bad_file_is_not_imported(tmp_path: Path) -> None:
    bad = tmp_path / "broken.npy"
    np.save(bad, np.zeros((5, 4)), allow_pickle=False)

    with pytest.raises(TrackError, match=r"broken\.npy"):
        import_track(bad)
    assert list(user_tracks_dir().iterdir()) == []


def test_save_generated_track_is_idempotent() -> None:
    track = generate_track(5)

    first = save_user_track(track)
    second = save_user_track(track)

    assert first == second
    assert first.name == "generated-5"
    assert resolve_track("generated-5").content_hash == track.content_hash
    with pytest.raises(TrackError, match="already imported"):
        save_user_track(generate_track(6).renamed("generated-5"))


def test_a_hand_copied_track_without_sidecar_is_listed(deepracer_dir: Path) -> None:
    target = user_tracks_dir() / "copied.npy"
    target.write_bytes((deepracer_dir / "tracks" / "Bowtie_track.npy").read_bytes())

    info = list_tracks()[-1]

    assert info.name == "copied"
    assert info.length_m == pytest.approx(17.43, abs=0.01)
    assert info.description == ""


def test_an_unreadable_user_file_is_listed_with_its_problem() -> None:
    (user_tracks_dir() / "junk.npy").write_text("not a track", encoding="utf-8")

    info = list_tracks()[-1]

    assert info.name == "junk"
    assert "cannot be used" in info.description
    with pytest.raises(TrackError, match=r"junk\.npy"):
        resolve_track("junk")


def test_sidecar_yaml_is_read_safely(deepracer_dir: Path, tmp_path: Path) -> None:
    import_track(deepracer_dir / "tracks" / "Oval_track.npy", "oval")
    marker = tmp_path / "yaml-ran-code"
    sidecar = user_tracks_dir() / "oval.yaml"
    sidecar.write_text(
        f"description: !!python/object/apply:os.system ['touch {marker}']\n", encoding="utf-8"
    )

    info = list_tracks()[-1]

    assert not marker.exists()
    assert info.name == "oval"
    assert info.length_m == pytest.approx(19.55, abs=0.01)


def test_sidecar_describes_the_import(deepracer_dir: Path) -> None:
    source = deepracer_dir / "tracks" / "Oval_track.npy"
    import_track(source, "oval", description="Club night track")

    meta = yaml.safe_load((user_tracks_dir() / "oval.yaml").read_text(encoding="utf-8"))

    assert meta["description"] == "Club night track"
    assert meta["source"] == str(source.resolve())
    assert meta["reversed"] is False
    assert meta["sha256"] == load_track(source).content_hash

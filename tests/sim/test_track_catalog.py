"""Resolving track names: built-in tracks, AWS DeepRacer's official tracks by world or console
name, a racer's imported tracks, and plain file paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sim.foundation.home import user_tracks_dir
from sim.foundation.remedies import Fix, Note
from sim.tracks.catalog import (
    TrackInfo,
    find_track_by_hash,
    find_track_info,
    import_problem,
    import_track,
    list_tracks,
    resolve_track,
    save_user_track,
)
from sim.tracks.generator import generate_track
from sim.tracks.track import TrackError, load_track

BUILTIN = ["beginner-oval", "hairpin-circuit", "bowtie-chicane", "speedway", "grand-prix"]
REAL = ["Bowtie_track", "Oval_track", "reInvent2019_wide", "reinvent_base"]
OFFICIAL_COUNT = 127


def test_builtin_tracks_are_listed_first_with_their_facts() -> None:
    infos = list_tracks()[: len(BUILTIN)]

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


def test_every_official_track_is_listed_after_the_builtin_ones() -> None:
    infos = list_tracks()
    official = [info for info in infos if info.kind == "official"]

    assert len(infos) == len(BUILTIN) + OFFICIAL_COUNT
    assert len(official) == OFFICIAL_COUNT
    assert infos[len(BUILTIN)].kind == "official"
    reinvent = next(info for info in official if info.name == "reinvent_base")
    assert reinvent.console_name == "re:Invent 2018"
    assert reinvent.title == "re:Invent 2018 (reinvent_base)"
    assert (reinvent.length_m, reinvent.width_m) == (17.71, 0.762)
    assert reinvent.direction == "counter-clockwise"
    dated = [info.release_date for info in official if info.release_date]
    assert dated == sorted(dated)  # oldest first, the console's never-listed files last


@pytest.mark.parametrize(
    ("name", "world"),
    [
        ("reinvent_base", "reinvent_base"),
        ("re:Invent 2018", "reinvent_base"),
        ("RE:INVENT 2018", "reinvent_base"),
        ("Reinvent_Base", "reinvent_base"),
        ("Expedition Loop", "red_star_open"),
        ("ace speedway", "2022_april_open"),  # the console's own variant of three
        ("A to Z Speedway", "reInvent2019_wide"),
        ("2022_april_open_cw", "2022_april_open_cw"),
    ],
)
def test_official_tracks_resolve_by_world_or_console_name(name: str, world: str) -> None:
    track = resolve_track(name)

    assert track.name == world
    assert track.content_hash == find_track_info(world).content_hash


def test_a_console_name_shared_by_two_directions_asks_which() -> None:
    with pytest.raises(TrackError) as caught:
        resolve_track("2022 re:Invent Championship")

    message = str(caught.value)
    assert "2022_reinvent_champ_ccw (counter-clockwise)" in message
    assert "2022_reinvent_champ_cw (clockwise)" in message


def test_the_straight_test_road_is_listed_but_cannot_be_raced() -> None:
    info = find_track_info("Straight_track")

    assert not info.lappable
    with pytest.raises(TrackError, match=r"not a loop.*reinvent_base"):
        resolve_track("Straight_track")


def test_unknown_name_suggests_close_names_in_one_sentence() -> None:
    with pytest.raises(TrackError) as caught:
        resolve_track("reinvent")

    message = str(caught.value)
    assert "'reinvent'" in message
    assert "'reinvent_base'" in message
    assert "tracks list" in message
    assert "tracks import" in message
    assert message.count(". ") == 0 and message.endswith(".")


def test_official_identity_equals_the_same_file_imported_by_hand(deepracer_dir: Path) -> None:
    source = deepracer_dir / "tracks" / "reinvent_base.npy"

    imported = import_track(source, "my-reinvent")

    assert resolve_track("my-reinvent").content_hash == resolve_track("reinvent_base").content_hash
    assert find_track_by_hash(imported.content_hash) == find_track_info("reinvent_base")


def test_importing_an_official_file_under_its_own_name_copies_nothing(
    deepracer_dir: Path,
) -> None:
    info = import_track(deepracer_dir / "tracks" / "reinvent_base.npy")

    assert info.kind == "official"
    assert list(user_tracks_dir().iterdir()) == []


def test_an_older_import_named_like_an_official_track_is_shown_as_hidden(
    deepracer_dir: Path,
) -> None:
    # Imported by hand before racer-tui shipped the official tracks, with other content.
    target = user_tracks_dir() / "reinvent_base.npy"
    target.write_bytes((deepracer_dir / "tracks" / "Oval_track.npy").read_bytes())

    hidden = list_tracks()[-1]

    assert (hidden.name, hidden.kind) == ("reinvent_base", "imported")
    assert "import the file again under another name" in hidden.description
    assert resolve_track("reinvent_base").length == pytest.approx(17.71, abs=0.01)


def test_a_track_is_found_by_content_hash_without_its_name(deepracer_dir: Path) -> None:
    copied = user_tracks_dir() / "hand-copied.npy"
    copied.write_bytes((deepracer_dir / "tracks" / "Bowtie_track.npy").read_bytes())
    generated = save_user_track(generate_track(3))

    assert find_track_by_hash(resolve_track("speedway").content_hash) == find_track_info("speedway")
    assert find_track_by_hash(generated.content_hash) == generated
    found = find_track_by_hash(resolve_track("Bowtie_track").content_hash)
    assert found is not None and found.name == "Bowtie_track"  # the official one first
    assert find_track_by_hash("0" * 64) is None


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
    name = f"club-{stem}"

    info = import_track(source, name, description="From the AWS console.")

    assert info == TrackInfo(
        name=name,
        description="From the AWS console.",
        length_m=round(load_track(source).length, 2),
        width_m=round(load_track(source).width, 3),
        direction="counter-clockwise",
        kind="imported",
        path=user_tracks_dir() / f"{name}.npy",
        content_hash=load_track(source).content_hash,
    )
    resolved = resolve_track(name)
    assert np.array_equal(resolved.points, load_track(source).points)
    assert resolved.description == "From the AWS console."
    assert list_tracks()[-1].name == name


def test_importing_twice_is_refused(deepracer_dir: Path) -> None:
    source = deepracer_dir / "tracks" / "reinvent_base.npy"
    import_track(source, "club")

    with pytest.raises(TrackError, match=r"already imported.*--name"):
        import_track(source, "club")
    with pytest.raises(TrackError, match="already imported"):
        import_track(source, "CLUB")  # one file on case-insensitive disks

    again = import_track(source, "reinvent-copy")
    assert again.name == "reinvent-copy"


def test_a_taken_name_names_its_remedy_for_any_front_end(deepracer_dir: Path) -> None:
    source = deepracer_dir / "tracks" / "reinvent_base.npy"
    import_track(source, "club")
    with pytest.raises(TrackError) as raised:
        import_track(source, "club")
    assert raised.value.fix is Fix.RENAME
    assert raised.value.problem == "a track named 'club' is already imported"


def test_import_problem_says_what_an_import_would_meet_and_keeps_nothing(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    oval = deepracer_dir / "tracks" / "Oval_track.npy"
    assert import_problem(oval, "club") is None
    # The shipped file under its own name: the import would say it is already here.
    assert import_problem(deepracer_dir / "tracks" / "reinvent_base.npy") is None
    taken = import_problem(oval, "reinvent_base")
    assert isinstance(taken, Note) and taken.fix is Fix.RENAME
    assert taken.problem == "'reinvent_base' is the name of an official track"
    assert (
        taken
        == "'reinvent_base' is the name of an official track; choose another name with --name."
    )
    bad_name = import_problem(oval, "has space")
    assert isinstance(bad_name, Note) and "letters, digits" in bad_name.problem
    broken = tmp_path / "broken.npy"
    broken.write_bytes(b"not a track")
    broken_problem = import_problem(broken)
    assert broken_problem is not None and "is not a NumPy .npy file" in broken_problem
    assert not isinstance(broken_problem, Note)  # the file, not its name, is the problem
    assert list(user_tracks_dir().iterdir()) == []


def test_import_reversed_runs_clockwise(deepracer_dir: Path) -> None:
    info = import_track(deepracer_dir / "tracks" / "Oval_track.npy", "oval-backwards", reverse=True)

    assert info.direction == "clockwise"
    assert resolve_track("oval-backwards").direction == "clockwise"


def test_a_builtin_or_official_name_cannot_be_taken(deepracer_dir: Path) -> None:
    with pytest.raises(TrackError, match=r"built-in track.*--name"):
        import_track(deepracer_dir / "tracks" / "Oval_track.npy", "speedway")
    with pytest.raises(TrackError, match=r"an official track.*--name"):
        import_track(deepracer_dir / "tracks" / "Oval_track.npy", "REINVENT_BASE")


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

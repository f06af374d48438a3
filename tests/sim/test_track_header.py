"""A track file's .npy header is checked against the file before anything is allocated for
it: a 600-byte file that claims 10^11 rows is refused in one sentence, never a MemoryError."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from numpy.lib import format as npy_format

from racer_tui.cli.main import main
from sim.tracks.track import TrackError, load_track


def forged(path: Path, shape: tuple[int, ...], descr: str = "<f8", rows_held: int = 5) -> Path:
    """A .npy file whose header claims `shape` but which holds only `rows_held` rows."""
    buffer = io.BytesIO()
    header = {"descr": descr, "fortran_order": False, "shape": shape}
    npy_format.write_array_header_1_0(buffer, header)
    buffer.write(np.zeros((rows_held, 6)).tobytes())
    path.write_bytes(buffer.getvalue())
    return path


def load_error(path: Path) -> str:
    with pytest.raises(TrackError) as caught:
        load_track(path)
    return str(caught.value)


def test_a_header_claiming_more_rows_than_the_file_holds_is_refused(tmp_path: Path) -> None:
    path = forged(tmp_path / "huge.npy", (10**11, 6))
    assert path.stat().st_size < 1000

    message = load_error(path)

    assert message.startswith(f"{path}: its header claims 100,000,000,000 rows")
    assert "holds only 240 bytes" in message
    assert "export the track again" in message


def test_a_truncated_track_is_refused_by_its_header(tmp_path: Path) -> None:
    full = tmp_path / "full.npy"
    np.save(full, np.zeros((50, 6)))
    cut = tmp_path / "cut.npy"
    cut.write_bytes(full.read_bytes()[:-10])

    assert "damaged or forged" in load_error(cut)


def test_an_object_header_is_refused_before_reading_its_data(tmp_path: Path) -> None:
    path = forged(tmp_path / "objects.npy", (3, 6), descr="|O")

    assert "pickled" in load_error(path)


@pytest.mark.parametrize("descr", ["<c16", "|b1", "<U4", "<M8[s]"])
def test_a_header_naming_no_plain_number_type_is_refused(tmp_path: Path, descr: str) -> None:
    path = forged(tmp_path / "typed.npy", (5, 6), descr=descr)

    assert "a track is an array of numbers" in load_error(path)


def test_a_header_with_a_wrong_shape_is_refused(tmp_path: Path) -> None:
    path = forged(tmp_path / "flat.npy", (30,))

    assert "has shape (30,)" in load_error(path)


def test_float32_and_big_endian_tracks_still_load(tmp_path: Path) -> None:
    theta = np.linspace(0, 2 * np.pi, 60)
    ring = np.stack(
        [f(theta) * radius for radius in (3.0, 2.5, 3.5) for f in (np.cos, np.sin)], axis=1
    )
    ring[-1] = ring[0]
    for dtype in ("<f4", ">f8"):
        path = tmp_path / f"ring-{dtype[1:]}.npy"
        np.save(path, ring.astype(dtype))
        assert len(load_track(path).points) == 60


@pytest.mark.parametrize(
    "command",
    [["tracks", "import"], ["tracks", "show"], ["model", "new", "forged-model", "--track"]],
)
def test_the_commands_that_read_a_track_refuse_a_forged_header_with_exit_2(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, command: list[str]
) -> None:
    path = forged(tmp_path / "huge.npy", (10**11, 6))

    code = main([*command, str(path)])

    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert "huge.npy: its header claims 100,000,000,000 rows" in err
    assert "Traceback" not in err and "MemoryError" not in err

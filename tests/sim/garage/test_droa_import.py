"""Importing DeepRacer on AWS's model downloads: `virtualmodel-*.tar.gz` and
`physicalmodel-*.tar.gz` as DRoA writes them (built from the real DeepRacer files)."""

from __future__ import annotations

import gzip
import io
import tarfile
from pathlib import Path

import pytest
import yaml

from sim.car_archive.archive import read_car_archive
from sim.deepracer.car_look import car_look
from sim.deepracer.files import read_evaluation_metrics
from sim.garage.folder import ModelError, models_dir
from sim.garage.importing import import_model
from sim.garage.summary import training_summary
from tests.sim.garage.droa_archives import (
    physical_model_archive,
    virtual_model_archive,
    virtual_model_members,
    write_archive,
)

NO_WEIGHTS = ("model/model_30.pb", "model/deepracer_checkpoints.json")


def _graph_bytes(archive: Path) -> bytes:
    with tarfile.open(archive) as tar:
        member = tar.extractfile("model/model_30.pb")
        assert member is not None
        return member.read()


def test_a_virtual_model_imports_with_its_direction_weights_metrics_and_look(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    archive = virtual_model_archive(deepracer_dir, tmp_path / "downloads")
    result = import_model(archive)
    folder = result.folder
    assert folder.name == "sample-model"
    params = folder.training_params()
    # WORLD_NAME 2022_april_open with TRACK_DIRECTION_CLOCKWISE: true is the clockwise file.
    assert params.world_name == "2022_april_open_cw"
    assert (
        "DeepRacer on AWS trained it on 2022_april_open clockwise "
        "(TRACK_DIRECTION_CLOCKWISE: true): it is set up on 2022_april_open_cw."
    ) in [str(note) for note in result.notes]
    # It drives with the best checkpoint's frozen graph, byte for byte.
    car = read_car_archive(folder.car_archive_file)
    with tarfile.open(folder.car_archive_file) as tar:
        graph = tar.extractfile("agent/model.pb")
        assert graph is not None and graph.read() == _graph_bytes(archive)
    assert car.metadata.training_algorithm == "clipped_ppo"
    # The training history, and each evaluation stamped with its file's ISO time.
    assert training_summary(folder)["episodes"] == 541  # deepracer-for-cloud's real ones
    stamps = sorted(path.name for path in (folder.path / "metrics").glob("EvaluationMetrics-*"))
    assert stamps == [
        "EvaluationMetrics-20260724162005.json",  # metrics/evaluation
        "EvaluationMetrics-20260725090041.json",  # metrics/submission
    ]
    trials = read_evaluation_metrics(folder.path / "metrics" / stamps[0])
    assert [t.trial for t in trials] == [1, 2, 3]
    # The logs come along as DRoA named them; the car keeps its shell and colour.
    logs = sorted(p.name for p in (folder.path / "logs" / "training").iterdir())
    assert logs == [
        "2026-07-24T15:06:12.345Z-deepracerindy-training-Ta1b2c3d4e5f6g7-simulation.log",
        "2026-07-24T15:06:12.345Z-deepracerindy-training-Ta1b2c3d4e5f6g7-training.log",
    ]
    look = car_look(params.extra)
    assert look is not None and look.describe() == "DeepRacer, orange"
    assert params.extra["IMPORTED_FROM"] == str(archive.resolve())
    # Nothing of the scratch folder is left behind.
    assert not list(Path(tmp_path).glob("racer-import-*"))


@pytest.mark.parametrize(
    ("clockwise", "world"),
    [(True, "2022_april_open_cw"), (False, "2022_april_open_ccw"), ("true", "2022_april_open_ccw")],
)
def test_the_direction_is_read_as_droa_reads_it(
    deepracer_dir: Path, tmp_path: Path, clockwise: object, world: str
) -> None:
    # DRoA's import takes only the YAML boolean true as clockwise (`=== true`). Without
    # its weights: running the graph has nothing to do with the track.
    archive = virtual_model_archive(
        deepracer_dir, tmp_path, params={"TRACK_DIRECTION_CLOCKWISE": clockwise}, drop=NO_WEIGHTS
    )
    assert import_model(archive).folder.training_params().world_name == world


def test_a_one_direction_track_has_no_direction_key(deepracer_dir: Path, tmp_path: Path) -> None:
    archive = virtual_model_archive(
        deepracer_dir,
        tmp_path,
        params={"WORLD_NAME": "Albert", "TRACK_DIRECTION_CLOCKWISE": None},
        drop=NO_WEIGHTS,
    )
    assert import_model(archive).folder.training_params().world_name == "Albert"


def test_a_direction_droa_does_not_allow_is_refused_in_its_words(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    # Yun Speedway (Albert) runs clockwise only.
    archive = virtual_model_archive(
        deepracer_dir,
        tmp_path,
        params={"WORLD_NAME": "Albert", "TRACK_DIRECTION_CLOCKWISE": False},
    )
    with pytest.raises(ModelError) as raised:
        import_model(archive)
    message = str(raised.value)
    assert message.startswith(
        "Invalid track configuration. Track Albert is not available in direction COUNTER_CLOCKWISE."
    )
    assert "TRACK_DIRECTION_CLOCKWISE" in message
    assert not list(models_dir().iterdir())


def test_a_physical_model_is_the_car_archive_named_as_its_model(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    archive = physical_model_archive(deepracer_dir, tmp_path)
    result = import_model(archive)
    assert result.folder.name == "sample-model"
    assert result.folder.has_car_archive()


def test_a_virtual_model_without_weights_starts_untrained(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    archive = virtual_model_archive(deepracer_dir, tmp_path, drop=NO_WEIGHTS)
    result = import_model(archive)
    assert not result.folder.has_car_archive()
    assert any("untrained" in str(note) for note in result.notes)


def _tar_with(member: tarfile.TarInfo, data: bytes = b"") -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        tar.addfile(member, io.BytesIO(data) if member.isreg() else None)
    return buffer.getvalue()


def test_an_archive_with_no_model_says_what_it_is_not(tmp_path: Path) -> None:
    archive = write_archive(tmp_path / "holiday.tar.gz", {"photos/beach.jpg": b"\xff\xd8"})
    with pytest.raises(ModelError, match="holds no model: neither a car model"):
        import_model(archive)


@pytest.mark.parametrize("name", ["../escape.json", "/etc/model_metadata.json"])
def test_a_member_outside_the_archive_is_refused(tmp_path: Path, name: str) -> None:
    info = tarfile.TarInfo(name)
    info.size = 2
    archive = tmp_path / "virtualmodel-bad.tar.gz"
    archive.write_bytes(_tar_with(info, b"{}"))
    with pytest.raises(ModelError, match="points outside the archive"):
        import_model(archive)
    assert not (tmp_path / "escape.json").exists()


def test_a_link_in_the_archive_is_refused(tmp_path: Path) -> None:
    info = tarfile.TarInfo("model_metadata.json")
    info.type = tarfile.SYMTYPE
    info.linkname = "/etc/passwd"
    archive = tmp_path / "virtualmodel-link.tar.gz"
    archive.write_bytes(_tar_with(info))
    with pytest.raises(ModelError, match="is a link or special file"):
        import_model(archive)


def test_a_member_larger_than_its_kind_may_be_is_refused_before_it_is_written(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    # A header that claims 2 GB for training_params.yaml: refused on the claim.
    members = virtual_model_members(deepracer_dir)
    metadata = tarfile.TarInfo("model_metadata.json")
    metadata.size = len(members["model_metadata.json"])
    padding = b"\0" * (-metadata.size % tarfile.BLOCKSIZE)
    big = tarfile.TarInfo("training_params.yaml")
    big.size = 2_000_000_000  # its data never comes: the header must be enough
    raw = metadata.tobuf() + members["model_metadata.json"] + padding + big.tobuf()
    archive = tmp_path / "virtualmodel-huge.tar.gz"
    archive.write_bytes(gzip.compress(raw))
    with pytest.raises(ModelError, match=r"training_params.yaml is 2,000,000,000 bytes"):
        import_model(archive)


def test_a_truncated_archive_is_one_sentence(deepracer_dir: Path, tmp_path: Path) -> None:
    archive = virtual_model_archive(deepracer_dir, tmp_path)
    archive.write_bytes(archive.read_bytes()[:5000])
    with pytest.raises(ModelError, match="not a complete gzip-compressed tar archive"):
        import_model(archive)


def test_the_archive_s_training_params_keep_droa_s_keys(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    archive = virtual_model_archive(
        deepracer_dir,
        tmp_path,
        params={"BODY_SHELL_TYPE": "f1_car_tron_05", "CAR_COLOR": None},
        drop=NO_WEIGHTS,
    )
    folder = import_model(archive).folder
    written = yaml.safe_load(folder.training_params_file.read_text())
    assert written["BODY_SHELL_TYPE"] == "f1_car_tron_05"
    assert "CAR_COLOR" not in written
    look = car_look(written)
    assert look is not None and look.describe() == "Tron, sky blue (f1_car_tron_05)"

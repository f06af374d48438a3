"""Car archives are untrusted input: the real DeepRacer one reads, bad ones are refused in
one sentence that names the file and what is wrong, and nothing is written to disk."""

from __future__ import annotations

import io
import json
import tarfile
from pathlib import Path

import pytest

import sim.car_archive.archive as archive_module
from sim.car_archive.archive import CarArchive, read_car_archive
from sim.car_archive.errors import CarModelError
from tests.sim.car_export.graphs import (
    METADATA,
    GraphWriter,
    camera_policy_graph,
    one_sentence,
    write_archive,
)


def refusal(path: Path) -> str:
    with pytest.raises(CarModelError) as caught:
        read_car_archive(path)
    message = str(caught.value)
    assert one_sentence(message), message
    assert path.name in message
    return message


def test_the_deepracer_trained_archive_reads_with_its_metadata_and_tensor_names(
    sample_archive: CarArchive,
) -> None:
    assert sample_archive.name == "sample-model"
    assert sample_archive.sensor == "FRONT_FACING_CAMERA"
    assert sample_archive.input_node.endswith("network_0/FRONT_FACING_CAMERA/FRONT_FACING_CAMERA")
    assert sample_archive.output_node.endswith("network_1/ppo_head_0/policy")
    space = sample_archive.metadata.action_space
    assert space.kind == "discrete" and len(space.actions) == 12
    assert (space.actions[6].steering_angle, space.actions[6].speed) == (0, 2.0)
    assert sample_archive.metadata.neural_network == "DEEP_CONVOLUTIONAL_NETWORK_SHALLOW"
    ops = sample_archive.graph.ops
    assert {"Conv2D", "MatMul", "Softmax", "Placeholder"} <= ops


def test_a_written_archive_reads_and_tar_s_directory_entries_are_allowed(tmp_path: Path) -> None:
    path = write_archive(tmp_path / "mine.tar.gz", directories=["./", "agent"])
    archive = read_car_archive(path)
    assert archive.name == "mine"
    assert len(archive.content_hash) == 64


def test_same_members_same_hash_other_weights_other_hash(tmp_path: Path) -> None:
    one = read_car_archive(write_archive(tmp_path / "one.tar.gz"))
    two = read_car_archive(write_archive(tmp_path / "two.tar.gz"))
    other = read_car_archive(
        write_archive(tmp_path / "other.tar.gz", graph=camera_policy_graph(seed=1))
    )
    assert one.content_hash == two.content_hash != other.content_hash


@pytest.mark.parametrize(
    "name", ["../model_metadata.json", "/etc/model_metadata.json", "agent/../../model.pb"]
)
def test_a_member_outside_the_archive_is_refused(tmp_path: Path, name: str) -> None:
    members = {name: b"{}", "agent/model.pb": camera_policy_graph()}
    message = refusal(write_archive(tmp_path / "bad.tar.gz", members))
    assert "points outside the archive" in message


def test_files_the_car_ignores_are_skipped_unread(tmp_path: Path) -> None:
    """deepracer-for-cloud's car upload tars a whole model folder; the car ignores what is
    not a model file, and racer-tui never reads, extracts or runs it either."""
    members = {
        "model_metadata.json": json.dumps(METADATA).encode(),
        "agent/model.pb": camera_policy_graph(),
        "agent/run_me.py": b"import os; os.system('echo pwned')",
        "deepracer_checkpoints.json": b"{}",
    }
    archive = read_car_archive(write_archive(tmp_path / "extra.tar.gz", members))
    plain = read_car_archive(write_archive(tmp_path / "plain.tar.gz"))
    assert archive.content_hash == plain.content_hash


@pytest.mark.parametrize("name", ["model_2.pb", "agent/checkpoint", "agent/model"])
def test_a_second_model_file_is_refused_as_the_car_refuses_it(tmp_path: Path, name: str) -> None:
    members = {
        "model_metadata.json": json.dumps(METADATA).encode(),
        "agent/model.pb": camera_policy_graph(),
        name: b"weights",
    }
    message = refusal(write_archive(tmp_path / "two.tar.gz", members))
    assert "another model file" in message and name in message


def test_links_are_refused(tmp_path: Path) -> None:
    path = write_archive(tmp_path / "link.tar.gz", links={"agent/model.pb": "/etc/passwd"})
    assert "link" in refusal(path)


def test_a_missing_member_is_named(tmp_path: Path) -> None:
    members = {"model_metadata.json": json.dumps(METADATA).encode()}
    assert "there is no agent/model.pb" in refusal(write_archive(tmp_path / "m.tar.gz", members))


def test_an_oversized_member_is_refused_before_it_is_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write_archive(tmp_path / "big.tar.gz")
    monkeypatch.setattr(archive_module, "MAX_GRAPH_BYTES", 1000)
    assert "more than the 1,000 allowed" in refusal(path)


def test_an_oversized_archive_file_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write_archive(tmp_path / "big.tar.gz")
    monkeypatch.setattr(archive_module, "MAX_ARCHIVE_BYTES", 100)
    assert "more than the 100 a car archive may have" in refusal(path)


def test_a_small_file_that_unpacks_to_too_much_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A PAX header is read whole into memory by tarfile, whatever size it claims.
    path = tmp_path / "bomb.tar.gz"
    with tarfile.open(path, "w:gz", format=tarfile.PAX_FORMAT) as tar:
        info = tarfile.TarInfo("model_metadata.json")
        info.pax_headers = {"comment": "x" * 5_000_000}
        tar.addfile(info, io.BytesIO(b""))
    assert path.stat().st_size < 100_000
    monkeypatch.setattr(archive_module, "MAX_UNPACKED_BYTES", 1_000_000)
    assert "unpacks to more than" in refusal(path)


def test_a_truncated_archive_is_refused(tmp_path: Path) -> None:
    whole = write_archive(tmp_path / "whole.tar.gz").read_bytes()
    cut = tmp_path / "cut.tar.gz"
    cut.write_bytes(whole[: len(whole) // 2])
    assert "truncated or corrupt" in refusal(cut)


def test_a_plain_file_is_not_an_archive(tmp_path: Path) -> None:
    path = tmp_path / "notes.tar.gz"
    path.write_text("not an archive")
    assert "gzip-compressed tar archive" in refusal(path)


def test_a_truncated_graph_inside_the_archive_is_refused(tmp_path: Path) -> None:
    path = write_archive(tmp_path / "t.tar.gz", graph=camera_policy_graph()[:-50])
    message = refusal(path)
    assert "agent/model.pb" in message and "truncated" in message


def test_an_unknown_op_inside_the_archive_is_refused(tmp_path: Path) -> None:
    g = GraphWriter()
    g.placeholder("x", [-1, 4])
    g.op("py", "PyFunc", "x")
    message = refusal(write_archive(tmp_path / "op.tar.gz", graph=bytes(g)))
    assert "'PyFunc'" in message and "cannot run" in message


def test_bad_metadata_is_refused_through_deepracer_files(tmp_path: Path) -> None:
    bad = {**METADATA, "action_space_type": "discrete", "action_space": "fast"}
    message = refusal(write_archive(tmp_path / "meta.tar.gz", metadata=bad))
    assert "model_metadata.json" in message


def test_a_model_without_a_camera_is_refused_in_one_sentence(tmp_path: Path) -> None:
    lidar = {**METADATA, "sensor": ["LIDAR"]}
    assert "without a camera" in refusal(write_archive(tmp_path / "l.tar.gz", metadata=lidar))


def test_a_graph_without_the_car_s_tensor_names_is_refused(tmp_path: Path) -> None:
    g = GraphWriter()
    g.op("out", "Softmax", g.placeholder("x", [-1, 3]))
    assert "no output named" in refusal(write_archive(tmp_path / "n.tar.gz", graph=bytes(g)))


def test_reading_writes_nothing_to_disk(tmp_path: Path) -> None:
    path = write_archive(tmp_path / "a.tar.gz")
    before = sorted(tmp_path.rglob("*"))
    read_car_archive(path)
    assert sorted(tmp_path.rglob("*")) == before


def test_an_archive_holding_a_duplicate_member_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "dup.tar.gz"
    with tarfile.open(path, "w:gz") as tar:
        for name, data in (
            ("model_metadata.json", json.dumps(METADATA).encode()),
            ("./model_metadata.json", json.dumps(METADATA).encode()),
        ):
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    assert "appears twice" in refusal(path)

"""Bundles: a model hands over in one file, and a crafted file cannot run code or sneak in."""

from __future__ import annotations

import hashlib
import io
import json
import pickle
import zipfile
from pathlib import Path

import pytest

from sim.coach.reward_line import template_source
from sim.deepracer.files import parse_model_metadata
from sim.garage.bundle import (
    BUNDLE_REWARD_FILE,
    BundleError,
    check_safetensors,
    export_bundle,
    install_bundle,
    install_bundle_report,
    read_bundle,
)
from sim.garage.folder import ModelError, ModelFolder, model_content_hash, models_dir
from sim.garage.importing import import_model
from sim.garage.options import new_model
from tests.sim.garage.helpers import policy_bytes, write_training_state

CUSTOM_REWARD = "def reward_function(params):\n    return float(params['progress'])\n"


@pytest.fixture
def exported(trained_model: ModelFolder, tmp_path: Path) -> Path:
    trained_model.reward_file.write_text(CUSTOM_REWARD)
    write_training_state(trained_model, "finished")
    return export_bundle(trained_model, tmp_path / "veteran")


def test_export_then_read_gives_back_the_model(trained_model: ModelFolder, exported: Path) -> None:
    assert exported.name == "veteran.racer-bundle"
    bundle = read_bundle(exported)
    assert bundle.name == "veteran"
    assert bundle.metadata == trained_model.metadata()
    assert bundle.hyperparameters == trained_model.hyperparameters()
    assert bundle.policy_bytes == trained_model.policy_file.read_bytes()
    assert bundle.content_hash == trained_model.content_hash()
    assert bundle.reward_source == CUSTOM_REWARD
    assert bundle.training_params.world_name == "reinvent_base"
    assert bundle.training_summary["state"] == "finished"
    assert bundle.training_summary["steps"] == 123456
    assert bundle.evaluation is not None and bundle.evaluation[0].lap_time_seconds == 9.5
    assert bundle.evaluation_file == "evaluation-20250101120000.json"
    with zipfile.ZipFile(exported) as archive:
        manifest = json.loads(archive.read("manifest.json"))
    assert manifest["format_version"] == 1
    assert manifest["content_hash"] == bundle.content_hash
    assert {entry["name"] for entry in manifest["files"]} == {
        "model_metadata.json",
        "hyperparameters.json",
        "training_params.yaml",
        "training-summary.json",
        "evaluation.json",
        "reward_function.py",
        "policy.safetensors",
    }


def test_install_makes_the_same_car_and_never_uses_its_reward(exported: Path) -> None:
    report = install_bundle_report(exported, name="rival")
    folder = report.folder
    original = read_bundle(exported)
    assert folder.name == "rival"
    assert folder.content_hash() == original.content_hash
    assert folder.metadata() == original.metadata
    assert folder.best_evaluation_lap() == 9.5
    # The bundle's reward function is kept to read, not to run.
    assert folder.reward_source() == template_source("follow_center_line")
    assert (folder.path / BUNDLE_REWARD_FILE).read_text() == CUSTOM_REWARD
    assert any(BUNDLE_REWARD_FILE in note for note in report.notes)
    assert folder.training_params().extra["INSTALLED_FROM"] == str(exported.resolve())
    from sim.garage.summary import training_summary

    assert training_summary(folder)["steps"] == 123456


def test_install_under_the_bundles_own_name_and_through_import(
    exported: Path, trained_model: ModelFolder
) -> None:
    with pytest.raises(ModelError, match="'veteran' already exists"):
        install_bundle(exported)
    assert import_model(exported, name="copy").folder.content_hash() == trained_model.content_hash()


def test_an_unknown_track_falls_back_and_says_so(exported: Path, tmp_path: Path) -> None:
    doctored = _rebuild(
        exported,
        tmp_path / "other-track.racer-bundle",
        replace={"training_params.yaml": b"WORLD_NAME: far-away\nMAX_MINUTES: 20\n"},
    )
    report = install_bundle_report(doctored, name="far")
    assert report.folder.training_params().world_name == "reinvent_base"
    assert any("'far-away', which is not here" in note for note in report.notes)


def test_export_needs_a_trained_policy(model: ModelFolder, tmp_path: Path) -> None:
    with pytest.raises(ModelError, match="no trained policy to export; train it first"):
        export_bundle(model, tmp_path / "x.racer-bundle")


def test_a_real_trained_policy_round_trips_and_drives(tmp_path: Path) -> None:
    policy = pytest.importorskip("sim.training.policy")
    policy_driver = pytest.importorskip("sim.training.policy_driver")
    folder = new_model("driver")
    policy.save_policy(folder.policy_file, policy.build_network(folder.metadata()))
    bundle = read_bundle(export_bundle(folder, tmp_path / "driver"))
    driver = policy_driver.driver_for_bundle(bundle)
    assert driver.content_hash == folder.content_hash()
    assert driver.name == "driver"


# --- crafted bundles -------------------------------------------------------------------


def _rebuild(
    source: Path,
    target: Path,
    *,
    replace: dict[str, bytes] | None = None,
    add: dict[str, bytes] | None = None,
    drop: tuple[str, ...] = (),
    fix_manifest: bool = True,
    fix_content_hash: bool = False,
) -> Path:
    """A copy of a good bundle with members changed; the manifest is made to agree unless
    `fix_manifest` is False, so each test hits exactly the defence it is about."""
    with zipfile.ZipFile(source) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    manifest = json.loads(members.pop("manifest.json"))
    members.update(replace or {})
    members.update(add or {})
    for name in drop:
        members.pop(name)
    if fix_manifest:
        manifest["files"] = [
            {"name": name, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()}
            for name, data in members.items()
        ]
    if fix_content_hash:
        metadata = parse_model_metadata(members["model_metadata.json"].decode(), "test")
        manifest["content_hash"] = model_content_hash(metadata, members["policy.safetensors"])
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("manifest.json", json.dumps(manifest))
        for name, data in members.items():
            archive.writestr(name, data)
    target.write_bytes(buffer.getvalue())
    return target


class _CreatesAFile:
    """Unpickling this opens (creates) `marker`: the proof a loader ran code."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[object, tuple[str, str]]:
        return (open, (str(self.marker), "w"))


def _assert_rejected_without_trace(bundle: Path, match: str) -> None:
    with pytest.raises(BundleError, match=match):
        read_bundle(bundle)
    with pytest.raises(BundleError, match=match):
        install_bundle(bundle, name="intruder")
    assert not (models_dir() / "intruder").exists()
    assert [p.name for p in models_dir().iterdir()] == ["veteran"]


def test_a_pickle_payload_policy_is_rejected_and_never_runs(exported: Path, tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    payload = pickle.dumps({"policy.0.weight": _CreatesAFile(marker)})
    crafted = _rebuild(
        exported,
        tmp_path / "evil.racer-bundle",
        replace={"policy.safetensors": payload},
        fix_content_hash=True,  # a careful attacker makes every hash agree
    )
    _assert_rejected_without_trace(crafted, "not a safetensors file of tensors")
    assert not marker.exists()


def test_torch_save_output_is_rejected(exported: Path, tmp_path: Path) -> None:
    torch = pytest.importorskip("torch")
    marker = tmp_path / "pwned"
    buffer = io.BytesIO()
    torch.save({"weight": torch.zeros(3), "trap": _CreatesAFile(marker)}, buffer)
    crafted = _rebuild(
        exported,
        tmp_path / "torch.racer-bundle",
        replace={"policy.safetensors": buffer.getvalue()},
        fix_content_hash=True,
    )
    _assert_rejected_without_trace(crafted, "not a safetensors file of tensors")
    assert not marker.exists()


def test_an_extra_member_is_rejected(exported: Path, tmp_path: Path) -> None:
    crafted = _rebuild(exported, tmp_path / "extra.racer-bundle", add={"setup.py": b"import os"})
    _assert_rejected_without_trace(crafted, "unexpected member 'setup.py'")


@pytest.mark.parametrize(
    "name", ["../reward_function.py", "/etc/cron.d/x", "sub/policy.safetensors"]
)
def test_path_members_are_rejected(exported: Path, tmp_path: Path, name: str) -> None:
    crafted = _rebuild(exported, tmp_path / "path.racer-bundle", add={name: b"x"})
    _assert_rejected_without_trace(crafted, "unexpected member")
    assert not (tmp_path / "reward_function.py").exists()


def test_a_corrupted_member_fails_its_hash(exported: Path, tmp_path: Path) -> None:
    crafted = _rebuild(
        exported,
        tmp_path / "corrupt.racer-bundle",
        replace={"hyperparameters.json": b'{"lr": 0.001}'},
        fix_manifest=False,
    )
    _assert_rejected_without_trace(crafted, "hyperparameters.json does not match the sha256")


def test_swapped_weights_fail_the_content_hash(exported: Path, tmp_path: Path) -> None:
    crafted = _rebuild(
        exported,
        tmp_path / "swapped.racer-bundle",
        replace={"policy.safetensors": policy_bytes(seed=7)},
    )
    _assert_rejected_without_trace(crafted, "content hash does not match")


def test_a_zip_bomb_is_stopped_before_it_unpacks(exported: Path, tmp_path: Path) -> None:
    crafted = _rebuild(
        exported, tmp_path / "bomb.racer-bundle", replace={"policy.safetensors": bytes(70_000_000)}
    )
    assert crafted.stat().st_size < 1_000_000
    _assert_rejected_without_trace(crafted, "would unpack to 70,000,000 bytes")


def test_missing_members_and_non_bundles(exported: Path, tmp_path: Path) -> None:
    crafted = _rebuild(exported, tmp_path / "thin.racer-bundle", drop=("reward_function.py",))
    _assert_rejected_without_trace(crafted, "lacks reward_function.py")
    junk = tmp_path / "junk.racer-bundle"
    junk.write_bytes(b"PK\x03\x04 not really a zip")
    _assert_rejected_without_trace(junk, "not a racer-tui bundle")
    truncated = tmp_path / "cut.racer-bundle"
    truncated.write_bytes(exported.read_bytes()[:-200])
    _assert_rejected_without_trace(truncated, "not a racer-tui bundle")


def test_a_malformed_manifest_is_rejected(exported: Path, tmp_path: Path) -> None:
    with zipfile.ZipFile(exported) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    manifest = json.loads(members["manifest.json"])
    for change, match in (
        ({"format": "zip"}, "not a racer-tui bundle manifest"),
        ({"format_version": 99}, "format version 99 is not 1"),
        ({"name": "../../etc"}, "model name is missing or not a valid name"),
        ({"evaluation_file": "../x.json"}, "evaluation_file is not"),
    ):
        members["manifest.json"] = json.dumps({**manifest, **change}).encode()
        crafted = tmp_path / "manifest.racer-bundle"
        with zipfile.ZipFile(crafted, "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
        _assert_rejected_without_trace(crafted, match)


def _safetensors(header: dict[str, object], body: bytes) -> bytes:
    raw = json.dumps(header).encode()
    return len(raw).to_bytes(8, "little") + raw + body


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (b"", "not a safetensors file"),
        (
            _safetensors({"w": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]}}, b"\0" * 4),
            "does not fill",
        ),
        (
            _safetensors({"w": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]}}, b"\0" * 8),
            "does not fill",
        ),
        (
            _safetensors({"w": {"dtype": "OBJ", "shape": [1], "data_offsets": [0, 4]}}, b"\0" * 4),
            "numbers only",
        ),
        (
            _safetensors({"w": {"dtype": "F32", "shape": [-1], "data_offsets": [0, 4]}}, b"\0" * 4),
            "malformed",
        ),
        (_safetensors({"__metadata__": {"a": 1}}, b""), "metadata must map text to text"),
        (_safetensors({}, b""), "holds no tensors"),
        (
            _safetensors(
                {
                    "a": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]},
                    "b": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]},
                },
                b"\0" * 4,
            ),
            "overlap",
        ),
    ],
)
def test_safetensors_are_checked_by_hand(data: bytes, match: str) -> None:
    with pytest.raises(BundleError, match=match):
        check_safetensors(data, "policy")


def test_a_valid_safetensors_file_passes() -> None:
    header = check_safetensors(policy_bytes(), "policy")
    assert header["policy.0.weight"]["shape"] == [8, 21]

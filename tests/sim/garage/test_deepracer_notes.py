"""An export says when DeepRacer itself could not run the model; camera models it could."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import pytest

from sim.deepracer.files import MODEL_METADATA
from sim.garage.bundle import export_bundle
from sim.garage.deepracer_notes import export_notes
from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from sim.training.policy import build_network, save_policy

SHARED_METADATA = Path(__file__).parents[3] / ".." / "shared/deepracer/drfc-model/model"

CAMERAS = {"FRONT_FACING_CAMERA", "STEREO_CAMERAS", "LEFT_CAMERA", "observation"}
LIDARS = {"LIDAR", "SECTOR_LIDAR", "DISCRETIZED_SECTOR_LIDAR"}


def simapp_refusal(data: dict[str, object]) -> str | None:
    """Why DeepRacer's simulator would refuse this model_metadata.json, or None.

    The checks simapp makes before training or evaluating (`model_metadata.py`,
    `parse_model_metadata`; `action_space_configs.py`), written out for the test."""
    if "action_space" not in data:
        return "no action space"
    sensors = data.get("sensor", ["observation"])
    assert isinstance(sensors, list)
    if float(str(data.get("version", "2"))) < 2.0:
        sensors = ["observation"]
    if sum(name in CAMERAS for name in sensors) != 1:
        return "not exactly one camera"
    if sum(name in LIDARS for name in sensors) > 1:
        return "more than one lidar"
    unknown = [name for name in sensors if name not in CAMERAS | LIDARS]
    if unknown:
        return f"unknown sensors {unknown}"
    algorithm = str(data.get("training_algorithm", "clipped_ppo")).lower().strip()
    kind = str(data.get("action_space_type", "discrete")).lower().strip()
    if algorithm not in ("clipped_ppo", "sac") or kind not in ("discrete", "continuous"):
        return "unknown algorithm or action space type"
    space = data["action_space"]
    if kind == "continuous":
        assert isinstance(space, dict)
        for key in ("steering_angle", "speed"):
            if not space[key]["low"] < space[key]["high"]:
                return f"{key} bounds out of order"
    else:
        if algorithm == "sac":
            return "sac with a discrete action space"
        assert isinstance(space, list)
        if not all({"steering_angle", "speed"} <= set(action) for action in space):
            return "an action without steering_angle and speed"
    return None


def _exported_metadata(model: ModelFolder, tmp_path: Path) -> dict[str, object]:
    save_policy(model.policy_file, build_network(model.metadata()))
    bundle = export_bundle(model, tmp_path / model.name)
    with zipfile.ZipFile(bundle) as archive:
        data = json.loads(archive.read(MODEL_METADATA))
    assert isinstance(data, dict)
    return data


def test_the_oracle_accepts_a_real_deepracer_model() -> None:
    path = SHARED_METADATA / "model_metadata.json"
    if not path.is_file():
        pytest.skip("../shared/deepracer is not beside this checkout")
    assert simapp_refusal(json.loads(path.read_text(encoding="utf-8"))) is None


@pytest.mark.parametrize("continuous", [False, True])
def test_a_camera_model_exports_metadata_simapp_accepts(tmp_path: Path, continuous: bool) -> None:
    model = new_model("cam", sensors=["camera"], continuous=continuous)
    assert export_notes(model.metadata()) == ()
    assert simapp_refusal(_exported_metadata(model, tmp_path)) is None


def test_a_vector_model_exports_with_a_note_that_deepracer_needs_a_camera(
    tmp_path: Path, model: ModelFolder
) -> None:
    assert model.metadata().sensors == ("vector",)
    assert simapp_refusal(_exported_metadata(model, tmp_path)) is not None
    (note,) = export_notes(model.metadata())
    assert "VECTOR" in note and "DeepRacer itself requires a camera" in note
    assert note.endswith(".") and "\n" not in note


def test_a_model_without_a_camera_gets_the_note_too() -> None:
    model = new_model("laser", sensors=["lidar"])
    (note,) = export_notes(model.metadata())
    assert "without a camera" in note and "DeepRacer itself requires a camera" in note

"""Camera randomisation as a model keeps it: training_params.yaml keys, model specs, clones."""

from __future__ import annotations

import pytest
import yaml

from sim.deepracer.files import DeepRacerFileError, TrainingParams
from sim.garage.clone import clone_model
from sim.garage.folder import ModelError
from sim.garage.options import model_spec, new_model, spec_of
from sim.sensors.randomisation.settings import (
    CAMERA_RANDOMISATION_KEYS,
    MAX_STRENGTH,
    CameraRandomisation,
    camera_randomisation_keys,
    parse_camera_randomisation,
    read_camera_randomisation,
    with_camera_randomisation_keys,
)
from sim.training.config import model_env_config, training_config
from sim.training.trainer import RunOptions, Trainer

CAMERA = ["FRONT_FACING_CAMERA"]


def _stored(folder_params: TrainingParams) -> dict[str, object]:
    return {k: v for k, v in folder_params.extra.items() if k.startswith("CAMERA_")}


def test_settings_round_trip_through_a_model_folders_training_params() -> None:
    chosen = CameraRandomisation(light=0.5, noise=2.0, blur=0.0, pose=1.0, colours=1.5)
    folder = new_model("real", sensors=CAMERA, camera_randomisation=chosen)
    text = folder.training_params_file.read_text()
    stored = yaml.safe_load(text)
    assert {key: stored[key] for key in CAMERA_RANDOMISATION_KEYS} == {
        "CAMERA_RANDOMISATION_LIGHT": 0.5,
        "CAMERA_RANDOMISATION_NOISE": 2.0,
        "CAMERA_RANDOMISATION_BLUR": 0.0,
        "CAMERA_RANDOMISATION_POSE": 1.0,
        "CAMERA_RANDOMISATION_COLOURS": 1.5,
    }
    assert read_camera_randomisation(folder.training_params()) == chosen
    assert spec_of(folder).camera_randomisation == chosen
    # The trainer's environments get it; the folder's own env config (evaluations) not.
    trainer = Trainer(folder, lambda event: None, lambda: True, RunOptions(cars=2))
    assert trainer.config.camera_randomisation == chosen
    assert model_env_config(folder).camera_randomisation == CameraRandomisation.OFF


def test_a_model_without_the_keys_reads_as_off_and_writes_none() -> None:
    plain = new_model("plain", sensors=CAMERA)
    off = new_model("off", sensors=CAMERA, camera_randomisation=CameraRandomisation.OFF)
    for folder in (plain, off):
        assert _stored(folder.training_params()) == {}
        assert "CAMERA_RANDOMISATION" not in folder.training_params_file.read_text()
        assert spec_of(folder).camera_randomisation == CameraRandomisation.OFF
    # Byte for byte the same file as a model made without the option.
    assert off.training_params_file.read_bytes() == plain.training_params_file.read_bytes()
    # A DeepRacer file, which never has them.
    deepracer = TrainingParams.from_mapping({"WORLD_NAME": "reinvent_base"}, "x.yaml")
    assert read_camera_randomisation(deepracer) == CameraRandomisation.OFF
    assert camera_randomisation_keys(CameraRandomisation.OFF) == {}


def test_a_clone_keeps_the_randomisation_and_may_change_it() -> None:
    chosen = CameraRandomisation(noise=0.0)
    source = new_model("source", sensors=CAMERA, camera_randomisation=chosen)
    same = clone_model(source, "same")
    assert spec_of(same).camera_randomisation == chosen
    changed = clone_model(source, "changed", camera_randomisation=CameraRandomisation.OFF)
    assert spec_of(changed).camera_randomisation == CameraRandomisation.OFF
    assert _stored(changed.training_params()) == {}


def test_only_a_camera_model_can_ask_for_it() -> None:
    with pytest.raises(ModelError, match="camera randomisation needs a camera"):
        model_spec(sensors=["LIDAR"], camera_randomisation=CameraRandomisation())
    # Kept from a camera model's spec, it goes when the sensor changes.
    camera = model_spec(sensors=CAMERA, camera_randomisation=CameraRandomisation())
    assert camera.camera_randomisation == CameraRandomisation()
    lidar = model_spec(camera, sensors=["LIDAR"])
    assert lidar.camera_randomisation == CameraRandomisation.OFF
    # And a race type change leaves it alone.
    boxes = model_spec(camera, race_type="object-avoidance")
    assert boxes.camera_randomisation == CameraRandomisation()


def test_a_partial_or_boolean_key_set_reads_as_a_racer_means_it() -> None:
    assert read_camera_randomisation({"CAMERA_RANDOMISATION_NOISE": 0.5}) == (
        CameraRandomisation(light=0, noise=0.5, blur=0, pose=0, colours=0)
    )
    assert read_camera_randomisation(
        {"CAMERA_RANDOMISATION_LIGHT": True, "CAMERA_RANDOMISATION_BLUR": "false"}
    ) == CameraRandomisation(light=1.0, noise=0, blur=0, pose=0, colours=0)


@pytest.mark.parametrize("value", [-0.1, MAX_STRENGTH + 0.5, "lots", None, float("nan")])
def test_a_bad_value_is_one_sentence_naming_the_key(value: object) -> None:
    with pytest.raises(DeepRacerFileError, match=r"x\.yaml: CAMERA_RANDOMISATION_POSE must"):
        read_camera_randomisation({"CAMERA_RANDOMISATION_POSE": value}, "x.yaml")


def test_a_bad_stored_value_stops_training_with_a_model_error() -> None:
    folder = new_model("broken", sensors=CAMERA)
    params = folder.training_params()
    bad = TrainingParams.from_mapping(
        {**yaml.safe_load(params.to_yaml()), "CAMERA_RANDOMISATION_NOISE": 9}, "x"
    )
    with pytest.raises(ModelError, match="CAMERA_RANDOMISATION_NOISE must be a number"):
        training_config(model_env_config(folder), bad, "training_params.yaml")


def test_strengths_are_checked() -> None:
    with pytest.raises(ValueError, match="the blur strength must be from 0"):
        CameraRandomisation(blur=3.0)
    with pytest.raises(ValueError, match="the light strength must be a number"):
        CameraRandomisation(light=True)


def test_the_words_a_racer_types() -> None:
    assert parse_camera_randomisation("on") == CameraRandomisation()
    assert parse_camera_randomisation("off") == CameraRandomisation.OFF
    assert parse_camera_randomisation("light, noise=0.5,colour") == CameraRandomisation(
        light=1.0, noise=0.5, blur=0.0, pose=0.0, colours=1.0
    )
    with pytest.raises(ValueError, match="unknown camera randomisation 'fog'"):
        parse_camera_randomisation("fog")
    with pytest.raises(ValueError, match="the noise strength must be a number"):
        parse_camera_randomisation("noise=much")
    with pytest.raises(ValueError, match="from 0 \\(off\\) to 2"):
        parse_camera_randomisation("pose=5")
    assert CameraRandomisation.OFF.describe() == "off"
    assert CameraRandomisation(light=0, noise=0.5, blur=0, pose=1, colours=0).describe() == (
        "sensor noise 0.5, camera height and pitch 1"
    )


def test_an_edited_models_keys_are_replaced_and_the_others_kept() -> None:
    extra = {"NUMBER_OF_OBSTACLES": 3, "CAMERA_RANDOMISATION_NOISE": 2.0, "CLONED_FROM": "a"}
    assert with_camera_randomisation_keys(extra, CameraRandomisation.OFF) == {
        "NUMBER_OF_OBSTACLES": 3,
        "CLONED_FROM": "a",
    }
    turned_on = with_camera_randomisation_keys(extra, CameraRandomisation(blur=0.5))
    assert read_camera_randomisation(turned_on) == CameraRandomisation(blur=0.5)
    assert turned_on["NUMBER_OF_OBSTACLES"] == 3

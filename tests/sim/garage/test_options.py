"""Console-style options: the defaults, each option's effect, and errors that say the range."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sim.coach.reward_line import template_source
from sim.deepracer.files import default_hyperparameters
from sim.garage.folder import ModelError, models_dir
from sim.garage.options import (
    DEFAULT_MINUTES,
    DEFAULT_TRACK,
    default_model_spec,
    model_spec,
    new_model,
    parse_hp_assignments,
    parse_range,
    read_actions_file,
)
from sim.reward.errors import RewardFunctionError


def test_the_default_model() -> None:
    spec = default_model_spec()
    assert spec.track == DEFAULT_TRACK == "reinvent_base"  # re:Invent 2018, the league track
    assert spec.metadata.sensors == ("vector",)
    space = spec.metadata.action_space
    assert space.kind == "discrete"
    assert len(space.actions) == 10  # 5 steering levels x 2 speed levels
    assert {a.steering_angle for a in space.actions} == {-30.0, -15.0, 0.0, 15.0, 30.0}
    assert {a.speed for a in space.actions} == {1.5, 3.0}
    assert spec.reward_source == template_source("follow_center_line")
    # DeepRacer's defaults, but a larger batch and fewer epochs: fast on a 2-core CPU.
    assert spec.hyperparameters == {
        **default_hyperparameters(),
        "batch_size": 512,
        "num_epochs": 4,
    }
    assert spec.max_minutes == DEFAULT_MINUTES == 60.0


def test_grid_options_take_defaults_for_the_rest() -> None:
    space = model_spec(max_speed=4.0, speed_levels=3).metadata.action_space
    assert len(space.actions) == 15
    assert sorted({a.speed for a in space.actions}) == pytest.approx([4 / 3, 8 / 3, 4.0], abs=1e-3)
    assert max(a.steering_angle for a in space.actions) == 30.0


def test_sensors_take_deepracer_names() -> None:
    assert model_spec(sensors=["FRONT_FACING_CAMERA"]).metadata.sensors == ("camera",)
    assert model_spec(sensors=["LIDAR", "vector"]).metadata.sensors == ("lidar", "vector")


def test_continuous_ranges() -> None:
    space = model_spec(
        continuous=True, steering_range=(-20.0, 20.0), speed_range=(0.5, 3.5)
    ).metadata.action_space
    assert space.kind == "continuous"
    assert space.steering_range == (-20.0, 20.0)
    assert space.speed_range == (0.5, 3.5)
    full = model_spec(continuous=True).metadata.action_space
    assert full.steering_range == (-30.0, 30.0)
    assert full.speed_range == (0.1, 4.0)


def test_actions_file_as_a_list_or_a_metadata_file(tmp_path: Path) -> None:
    listing = tmp_path / "actions.json"
    listing.write_text(
        json.dumps([{"steering_angle": -10, "speed": 2}, {"steering_angle": 10, "speed": 2}])
    )
    assert len(model_spec(actions_file=listing).metadata.action_space.actions) == 2
    metadata = tmp_path / "model_metadata.json"
    metadata.write_text(
        json.dumps(
            {
                "action_space": {
                    "steering_angle": {"low": -5, "high": 5},
                    "speed": {"low": 1, "high": 2},
                },
                "action_space_type": "continuous",
            }
        )
    )
    assert read_actions_file(metadata).kind == "continuous"


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"steering_levels": 4}, "--steering-levels must be 3, 5 or 7, not 4"),
        ({"speed_levels": 5}, "--speed-levels must be 1, 2 or 3, not 5"),
        ({"max_steering": 45.0}, "--max-steering must be from 1 to 30 degrees, not 45"),
        ({"max_speed": 9.0}, "--max-speed must be from 0.1 to 4 m/s, not 9"),
        ({"sensors": ["radar"]}, "--sensor: unknown sensor 'radar'; choose from camera"),
        ({"sensors": ["LIDAR", "SECTOR_LIDAR"]}, "--sensor: choose either LIDAR or SECTOR_LIDAR"),
        ({"track": "atlantis"}, "--track: there is no track named 'atlantis'"),
        ({"reward": "best_reward"}, "--reward: 'best_reward' is neither a template"),
        ({"minutes": 0.0}, "--minutes must be from 1 to 100000"),
        ({"minutes": 0.5}, "--minutes must be from 1 to 100000"),
        (
            {"hyperparameters": {"lr": 0.5}},
            "--hp: lr must be a number from 1e-08 to 0.001, not 0.5",
        ),
        (
            {"hyperparameters": {"num_epochs": 11}},
            "--hp: num_epochs must be a whole number from 3 to 10",
        ),
        (
            {"hyperparameters": {"loss_type": "l1"}},
            "--hp: loss_type must be 'huber' or 'mean squared error'",
        ),
        (
            {"hyperparameters": {"gamma": 0.9}},
            "--hp: unknown hyperparameter 'gamma'; the tunable ones are",
        ),
        ({"continuous": True, "max_speed": 2.0}, "choose one way to give the action space"),
        ({"speed_range": (1.0, 2.0)}, "--steering-range and --speed-range need --continuous"),
    ],
)
def test_invalid_options_name_the_option_and_the_range(
    options: dict[str, object], message: str
) -> None:
    with pytest.raises(ModelError) as caught:
        new_model("nope", **options)
    assert message in str(caught.value)
    assert list(models_dir().iterdir()) == []


def test_hp_assignments_are_typed_by_their_key() -> None:
    values = parse_hp_assignments(["lr=0.0001", "batch_size=128", "loss_type=mean squared error"])
    assert values == {"lr": 0.0001, "batch_size": 128.0, "loss_type": "mean squared error"}
    checked = model_spec(hyperparameters=values).hyperparameters
    assert checked["batch_size"] == 128 and isinstance(checked["batch_size"], int)
    with pytest.raises(ModelError, match="write KEY=VALUE"):
        parse_hp_assignments(["lr"])
    with pytest.raises(ModelError, match="--hp: lr must be a number"):
        parse_hp_assignments(["lr=fast"])


def test_ranges_are_checked() -> None:
    assert parse_range("-20,25", "--steering-range", -30, 30, "degrees") == (-20.0, 25.0)
    for text in ("20", "a,b", "5,1", "-40,0", "nan,1"):
        with pytest.raises(ModelError, match="--steering-range must be LOW,HIGH in degrees"):
            parse_range(text, "--steering-range", -30, 30, "degrees")


def test_a_reward_file_is_loaded_before_anything_is_written(tmp_path: Path) -> None:
    broken = tmp_path / "reward.py"
    broken.write_text("def reward_function(params):\n    return params['speed' \n")
    with pytest.raises(RewardFunctionError, match=r"reward\.py"):
        new_model("careful", reward=str(broken))
    assert list(models_dir().iterdir()) == []
    good = tmp_path / "good.py"
    good.write_text("def reward_function(params):\n    return float(params['speed'])\n")
    folder = new_model("careful", reward=str(good))
    assert folder.reward_source() == good.read_text()


def test_a_template_by_name() -> None:
    folder = new_model("zigzag", reward="prevent_zigzag", minutes=5)
    assert folder.reward_source() == template_source("prevent_zigzag")
    assert folder.training_params().max_minutes == 5.0

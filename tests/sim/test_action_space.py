"""DeepRacer action spaces in model_metadata.json form."""

from __future__ import annotations

import numpy as np
import pytest

from sim.deepracer.action_space import ActionSpaceError, discrete_grid, parse_action_space


def test_discrete_list_maps_indices_to_targets() -> None:
    space = parse_action_space(
        [{"steering_angle": -30, "speed": 0.6, "index": 0}, {"steering_angle": 15.5, "speed": 2.5}],
        "discrete",
    )
    steering, speed = space.targets(np.array([1, 0]))
    assert steering.tolist() == [15.5, -30.0]
    assert speed.tolist() == [2.5, 0.6]
    assert space.max_speed == 2.5


def test_continuous_ranges_scale_normalised_actions() -> None:
    space = parse_action_space(
        {"steering_angle": {"low": -20, "high": 20}, "speed": {"low": 0.5, "high": 3.0}},
        "continuous",
    )
    steering, speed = space.targets(np.array([[-1.0, -1.0], [1.0, 1.0], [0.0, 0.0]]))
    assert steering.tolist() == [-20.0, 20.0, 0.0]
    assert speed.tolist() == [0.5, 3.0, 1.75]


def test_real_drfc_model_action_space_parses(deepracer_dir) -> None:  # type: ignore[no-untyped-def]
    import json

    metadata = json.loads((deepracer_dir / "drfc-model/model/model_metadata.json").read_text())
    space = parse_action_space(metadata["action_space"], metadata.get("action_space_type"))
    assert space.kind == "discrete"
    assert len(space.actions) == 14


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ([{"steering_angle": 45, "speed": 1}], "between -30 and 30"),
        ([{"steering_angle": 0, "speed": 5}], "between 0.1 and 4"),
        ([{"steering_angle": 0}], "steering_angle and a speed"),
        ([], "empty"),
        (
            {"steering_angle": {"low": 10, "high": -10}, "speed": {"low": 1, "high": 2}},
            "must be below",
        ),
        ({"speed": {"low": 1, "high": 2}}, "needs steering_angle"),
        ("fast", "must be a list"),
        ([{"steering_angle": "left", "speed": 1}], "must be a number"),
    ],
)
def test_bad_action_spaces_say_what_is_wrong(value: object, message: str) -> None:
    with pytest.raises(ActionSpaceError, match=message):
        parse_action_space(value)


def test_console_grid_builder_matches_deepracer_console() -> None:
    space = discrete_grid(max_steering=30, steering_levels=5, max_speed=3.0, speed_levels=3)
    assert len(space.actions) == 15
    assert sorted({a.steering_angle for a in space.actions}) == [-30.0, -15.0, 0.0, 15.0, 30.0]
    assert sorted({a.speed for a in space.actions}) == [1.0, 2.0, 3.0]
    with pytest.raises(ActionSpaceError, match="choose 3, 5 or 7"):
        discrete_grid(steering_levels=4)


def test_metadata_round_trip() -> None:
    space = discrete_grid(20, 3, 2.0, 2)
    assert parse_action_space(space.to_metadata(), "discrete") == space

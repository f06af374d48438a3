"""The editor's logic without the screen: form text to a checked spec, and saving edits."""

from __future__ import annotations

from dataclasses import replace

import pytest

from racer_tui.app.model_form import (
    CONTINUOUS,
    KEPT,
    FormError,
    action_space_of,
    grid_of,
    save_edit,
    spec_of_form,
    values_of,
)
from sim.deepracer.action_space import Action, ActionSpace, discrete_grid
from sim.garage.folder import ModelError, open_model
from sim.garage.options import default_model_spec, new_model
from tests.racer_tui.screens.tui_helpers import trained_model


def _fields(error: pytest.ExceptionInfo[FormError]) -> set[str]:
    return {problem.field for problem in error.value.problems}


def test_the_defaults_round_trip_through_the_form() -> None:
    spec = default_model_spec()
    values = values_of(spec, "ada")
    assert values.action_kind == "discrete"
    again = spec_of_form(values, base=spec, new_name_taken=set())
    assert again.metadata == spec.metadata
    assert again.hyperparameters == spec.hyperparameters
    assert again.reward_source == spec.reward_source


def test_every_bad_field_is_reported_at_once() -> None:
    spec = default_model_spec()
    values = replace(
        values_of(spec, "Ada"),
        max_speed="fast",
        max_minutes="0",
        hyperparameters={"batch_size": "1000", "lr": "abc", "loss_type": "huber"},
        reward_source="def reward_function(params):\n    return (",
    )
    with pytest.raises(FormError) as error:
        spec_of_form(values, base=spec, new_name_taken={"ada"})
    assert _fields(error) == {
        "name",
        "max-speed",
        "max-minutes",
        "hp-batch_size",
        "hp-lr",
        "reward",
    }
    messages = {problem.field: problem.message for problem in error.value.problems}
    assert "whole number from 32 to 512" in messages["hp-batch_size"]
    assert "line 2" in messages["reward"]


def test_continuous_ranges_must_be_ordered_and_in_limits() -> None:
    values = replace(
        values_of(default_model_spec()),
        action_kind=CONTINUOUS,
        steering_low="10",
        steering_high="-10",
        speed_low="0.5",
        speed_high="5",
    )
    with pytest.raises(FormError) as error:
        action_space_of(values)
    assert _fields(error) == {"speed-high"}
    values = replace(values, speed_high="3")
    with pytest.raises(FormError) as error:
        action_space_of(values)
    assert _fields(error) == {"steering-high"}
    space = action_space_of(replace(values, steering_low="-10", steering_high="10"))
    assert space.steering_range == (-10.0, 10.0) and space.speed_range == (0.5, 3.0)


def test_a_hand_written_action_list_is_kept_as_it_is() -> None:
    custom = ActionSpace(kind="discrete", actions=(Action(0.0, 1.0), Action(12.5, 2.2)))
    assert grid_of(custom) is None
    assert grid_of(discrete_grid(20, 3, 2.0, 2)) == (20.0, 3, 2.0, 2)
    spec = replace(
        default_model_spec(), metadata=replace(default_model_spec().metadata, action_space=custom)
    )
    values = values_of(spec)
    assert values.action_kind == KEPT
    assert action_space_of(values, kept=custom) is custom


def test_save_edit_rewrites_the_files_atomically_checked() -> None:
    folder = new_model("ada")
    spec = replace(default_model_spec(), track="speedway", max_minutes=5.0)
    save_edit(folder, spec)
    again = open_model("ada")
    assert again.training_params().world_name == "speedway"
    assert again.training_params().max_minutes == 5.0


def test_save_edit_refuses_a_new_shape_for_a_trained_policy() -> None:
    folder = trained_model("ada")
    before = folder.metadata_file.read_bytes()
    wider = replace(
        default_model_spec(),
        metadata=replace(default_model_spec().metadata, action_space=discrete_grid(30, 7, 3.0, 2)),
    )
    with pytest.raises(ModelError, match="clone the model"):
        save_edit(folder, wider)
    assert folder.metadata_file.read_bytes() == before

"""A model says when its policy learnt to drive another car than today's."""

from __future__ import annotations

import json
from pathlib import Path

from sim.deepracer.files import (
    EvaluationTrial,
    read_evaluation_physics,
    write_evaluation_metrics,
)
from sim.garage.bundle import export_bundle, install_bundle_report
from sim.garage.options import new_model
from sim.garage.overview import model_details
from sim.physics.labels import BEFORE_VERSIONING, CURRENT
from tests.sim.garage.helpers import add_policy, write_training_state

OTHER = "racer-tui/7" if CURRENT != "racer-tui/7" else "racer-tui/8"


def _trained_on(physics: str | None) -> dict[str, object]:
    folder = new_model("old-timer")
    add_policy(folder)
    write_training_state(folder, "finished")
    state = json.loads(folder.training_state_file.read_text())
    if physics is None:
        state.pop("physics", None)  # written before physics was recorded
    else:
        state["physics"] = physics
    folder.training_state_file.write_text(json.dumps(state))
    return model_details(folder)


def test_an_untrained_model_has_no_physics() -> None:
    folder = new_model("rookie")

    assert folder.trained_physics() is None
    assert model_details(folder)["physics_note"] is None


def test_a_policy_of_todays_physics_needs_no_note() -> None:
    assert _trained_on(CURRENT)["physics_note"] is None


def test_a_policy_of_another_physics_says_to_train_again() -> None:
    note = str(_trained_on(OTHER)["physics_note"])

    assert f"racer-tui physics {OTHER.split('/')[1]}" in note
    assert "train it again" in note


def test_a_policy_from_before_physics_was_recorded_counts_as_the_first() -> None:
    details = _trained_on(None)

    expected = None if CURRENT == BEFORE_VERSIONING else "racer-tui physics 1"
    if expected is None:
        assert details["physics_note"] is None
    else:
        assert expected in str(details["physics_note"])


def test_a_bundle_carries_the_physics_of_its_policy_and_of_its_laps(tmp_path: Path) -> None:
    folder = new_model("traveller")
    add_policy(folder)
    write_training_state(folder, "finished")
    state = json.loads(folder.training_state_file.read_text())
    folder.training_state_file.write_text(json.dumps({**state, "physics": OTHER}))
    write_evaluation_metrics(
        folder.evaluation_metrics_file("20250101120000"),
        [EvaluationTrial(100.0, 9600, 100, 9500, "Lap complete", trial=1)],
        physics=OTHER,
    )
    exported = export_bundle(folder, tmp_path / "traveller.racer-bundle")

    installed = install_bundle_report(exported, name="arrived").folder

    assert installed.trained_physics() == OTHER
    (evaluation,) = installed.evaluation_files()
    assert read_evaluation_physics(evaluation) == OTHER

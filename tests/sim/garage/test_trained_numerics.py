"""A model records how its training computed the policy (float32, or bfloat16
convolutions on a CPU with bfloat16 in hardware), as it records the physics it learnt:
`model show` says it, and a bundle carries it."""

from __future__ import annotations

import json
from pathlib import Path

from sim.garage.bundle import export_bundle, install_bundle_report
from sim.garage.folder import BF16_CONVOLUTIONS, FLOAT32, ModelFolder
from sim.garage.options import new_model
from sim.garage.summary import training_summary
from tests.sim.garage.helpers import add_policy, write_training_state


def _trained_in(name: str, numerics: object) -> ModelFolder:
    folder = new_model(name)
    add_policy(folder)
    write_training_state(folder, "finished")
    state = json.loads(folder.training_state_file.read_text())
    folder.training_state_file.write_text(json.dumps({**state, "numerics": numerics}))
    return folder


def test_an_untrained_model_and_one_trained_before_numerics_say_none() -> None:
    rookie = new_model("rookie")
    assert rookie.trained_numerics() is None
    older = new_model("older")
    add_policy(older)
    write_training_state(older, "finished")  # written before numerics were recorded
    assert older.trained_numerics() is None
    assert training_summary(older)["numerics"] is None


def test_the_numerics_of_a_training_are_the_models_and_travel_with_a_bundle(
    tmp_path: Path,
) -> None:
    folder = _trained_in("traveller", BF16_CONVOLUTIONS)
    assert folder.trained_numerics() == BF16_CONVOLUTIONS
    assert training_summary(folder)["numerics"] == BF16_CONVOLUTIONS
    exported = export_bundle(folder, tmp_path / "traveller.racer-bundle")
    installed = install_bundle_report(exported, name="arrived").folder
    assert installed.trained_numerics() == BF16_CONVOLUTIONS
    assert _trained_in("plain", FLOAT32).trained_numerics() == FLOAT32


def test_numerics_it_does_not_know_are_not_believed() -> None:
    assert _trained_in("odd", "fp8 [bold]magic").trained_numerics() is None
    assert _trained_in("odder", {"nested": 1}).trained_numerics() is None

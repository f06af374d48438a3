"""`racer-tui model export` says when DeepRacer itself could not run the exported model."""

from __future__ import annotations

from pathlib import Path

import pytest

from racer_tui.cli.main import main
from sim.garage.options import new_model
from sim.training.policy import build_network, save_policy


@pytest.mark.parametrize(("sensor", "noted"), [("vector", True), ("camera", False)])
def test_export_notes_a_model_deepracer_cannot_load(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, sensor: str, noted: bool
) -> None:
    model = new_model("exported", sensors=[sensor])
    save_policy(model.policy_file, build_network(model.metadata()))
    code = main(["model", "export", "exported", "-o", str(tmp_path / "exported")])
    out, _ = capsys.readouterr()
    assert code == 0 and "Exported exported to" in out
    notes = [line for line in out.splitlines() if line.startswith("Note: ")]
    if noted:
        assert len(notes) == 1 and "DeepRacer itself requires a camera" in notes[0]
    else:
        assert notes == []

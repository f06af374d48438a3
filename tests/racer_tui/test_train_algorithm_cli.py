"""`racer-tui train` refuses a sac model with one sentence and exit code 2."""

from __future__ import annotations

from dataclasses import replace

import pytest

from racer_tui.cli.main import main
from sim.deepracer.action_space import parse_action_space
from sim.deepracer.files import write_model_metadata
from sim.garage.options import new_model


def test_training_a_discrete_sac_model_is_a_user_error(capsys: pytest.CaptureFixture[str]) -> None:
    model = new_model("tiny")
    space = parse_action_space([{"steering_angle": 0.0, "speed": 1.0}])
    write_model_metadata(
        model.metadata_file,
        replace(model.metadata(), training_algorithm="sac", action_space=space),
    )
    code = main(["train", "tiny", "--minutes", "0.02", "--json"])
    out, err = capsys.readouterr()
    assert code == 2
    assert err.startswith("racer-tui: ") and "needs a continuous action space" in err
    assert len(err.strip().splitlines()) == 1
    assert out == ""  # no training child was started

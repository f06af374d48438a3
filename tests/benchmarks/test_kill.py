"""The kill script, at a small scale: a push, a pull and a training each killed at a random
moment, and concurrent writers; nothing is lost, duplicated or left corrupt."""

from __future__ import annotations

import json

import pytest

from benchmarks.app.kill import main


@pytest.mark.slow
def test_killed_pushes_pulls_and_trainings_lose_nothing(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["--sync-kills", "1", "--records", "150", "--writers", "3"]
    args += ["--train-kills", "1", "--train-window", "3", "--last-minutes", "0.03"]
    assert main([*args, "--races-each", "3", "--seed", "3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["problems"] == []
    assert (report["lost"], report["duplicated"], report["corrupt"]) == (0, 0, 0)
    parts = report["parts"]
    assert parts["push"]["runs"] == parts["pull"]["runs"] == 1
    assert parts["writers"]["runs"] == 3
    assert parts["train"]["runs"] == 1 and parts["train"]["killed_mid_way"] == 1

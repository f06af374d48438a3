"""Garage fixtures: models made the way a racer makes them."""

from __future__ import annotations

import pytest

from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from tests.sim.garage.helpers import add_evaluation, add_policy


@pytest.fixture
def model() -> ModelFolder:
    """A default model, untrained."""
    return new_model("rookie")


@pytest.fixture
def trained_model() -> ModelFolder:
    """A default model with a policy and one evaluation."""
    folder = new_model("veteran")
    add_policy(folder)
    add_evaluation(folder)
    return folder

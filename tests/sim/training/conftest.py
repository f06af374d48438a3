"""Fixtures for training tests: small models in the temporary garage."""

from __future__ import annotations

import pytest

from sim.garage.folder import ModelFolder
from sim.garage.options import new_model


@pytest.fixture
def model() -> ModelFolder:
    """The default model (`racer-tui model new`): re:Invent 2018, vector sensor."""
    return new_model("tiny")

"""League fixtures: a fresh league database per test."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from league.opening import open_league
from league.store import League


@pytest.fixture
def league_path(tmp_path: Path) -> Path:
    return tmp_path / "league.db"


@pytest.fixture
def league(league_path: Path) -> Iterator[League]:
    with open_league(league_path) as opened:
        yield opened

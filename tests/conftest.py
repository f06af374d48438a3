"""Shared fixtures. Every test runs with RACER_TUI_HOME in a temp dir: no real data is touched."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parent.parent
SHARED_DEEPRACER = REPO_ROOT.parent / "shared" / "deepracer"


@pytest.fixture(autouse=True)
def racer_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    home = tmp_path / "racer-home"
    monkeypatch.setenv("RACER_TUI_HOME", str(home))
    yield home


@pytest.fixture
def deepracer_dir() -> Path:
    """The real AWS DeepRacer files in ../shared/deepracer (skips when absent)."""
    if not SHARED_DEEPRACER.is_dir():
        pytest.skip(
            "../shared/deepracer is not beside this checkout; real DeepRacer files unavailable"
        )
    return SHARED_DEEPRACER

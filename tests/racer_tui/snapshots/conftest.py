"""Shared by the snapshot tests: a data folder at the same path on every run, so screens
that show paths (the garage's model folder, for example) draw the same characters."""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def fixed_home(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    name = request.node.name.replace("[", "-").replace("]", "")
    home = Path(tempfile.gettempdir()) / "racer-tui-snapshots" / name
    shutil.rmtree(home, ignore_errors=True)
    monkeypatch.setenv("RACER_TUI_HOME", str(home))
    yield home
    shutil.rmtree(home, ignore_errors=True)

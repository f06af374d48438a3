"""The one place that knows where racer-tui keeps its data.

`RACER_TUI_HOME` overrides the platform's user data directory; tests always set it to a
temporary directory so they never touch a real racer's garage or league.
"""

from __future__ import annotations

import os
from pathlib import Path

import platformdirs

HOME_ENV = "RACER_TUI_HOME"


def data_home() -> Path:
    """The data directory (created on first use)."""
    override = os.environ.get(HOME_ENV)
    root = Path(override) if override else Path(platformdirs.user_data_dir("racer-tui"))
    root.mkdir(parents=True, exist_ok=True)
    return root


def user_tracks_dir() -> Path:
    """Where `racer-tui tracks import` and `tracks generate --save` put tracks."""
    path = data_home() / "tracks"
    path.mkdir(parents=True, exist_ok=True)
    return path

"""The one place that knows where racer-tui keeps its data.

`RACER_TUI_HOME` overrides the platform's user data directory; tests always set it to a
temporary directory so they never touch a real racer's garage or league.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import platformdirs

HOME_ENV = "RACER_TUI_HOME"
# The league database file, when it is not `league.db` in the data directory (a host
# keeping one league per season, or a league file on a shared drive).
LEAGUE_ENV = "RACER_TUI_LEAGUE"
LEAGUE_FILE = "league.db"


def data_home() -> Path:
    """The data directory (created on first use)."""
    override = os.environ.get(HOME_ENV)
    root = Path(override) if override else Path(platformdirs.user_data_dir("racer-tui"))
    root.mkdir(parents=True, exist_ok=True)
    return root


@contextmanager
def home_at(path: Path) -> Iterator[Path]:
    """Use `path` as the data directory until the block ends (a benchmark's scratch home:
    it never touches the racer's own garage or league). Child processes started inside
    inherit it through the environment."""
    saved = os.environ.get(HOME_ENV)
    os.environ[HOME_ENV] = str(path)
    try:
        yield path
    finally:
        if saved is None:
            os.environ.pop(HOME_ENV, None)
        else:
            os.environ[HOME_ENV] = saved


def user_tracks_dir() -> Path:
    """Where `racer-tui tracks import` and `tracks generate --save` put tracks."""
    path = data_home() / "tracks"
    path.mkdir(parents=True, exist_ok=True)
    return path


def league_db_file() -> Path:
    """The league database: `RACER_TUI_LEAGUE` if set, else league.db in the data directory."""
    override = os.environ.get(LEAGUE_ENV)
    return Path(override).expanduser() if override else data_home() / LEAGUE_FILE

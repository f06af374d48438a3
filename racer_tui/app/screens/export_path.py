"""Where an export goes: the file name's ending chooses the format (the League screen's
leaderboard and the Nights screen's night both ask for one)."""

from __future__ import annotations

import os
from pathlib import Path

from sim.foundation.home import HOME_ENV, data_home

EXPORT_FORMATS = {".csv": "csv", ".json": "json", ".md": "markdown", ".markdown": "markdown"}


def export_folder() -> Path:
    """Where an export dialog proposes to write: the home folder, never the folder the app
    was started from (a host who started it in a clone wrote into the repository); with
    RACER_TUI_HOME set, that folder, so a league kept on one drive keeps its files there."""
    if os.environ.get(HOME_ENV):
        return data_home()
    return Path.home()


def check_export_path(text: str) -> str | None:
    """Why `text` cannot be exported to, or None."""
    suffix = Path(text).suffix.lower()
    if suffix not in EXPORT_FORMATS:
        return "End the file name with .csv, .json or .md to choose the format."
    if not Path(text).expanduser().parent.is_dir():
        return f"The folder {Path(text).expanduser().parent} does not exist; create it first."
    return None

"""A command's request to open the app instead of printing (`night projector`): the
command line never imports the app; its entry point (`racer_tui.cli.main`) does, and opens
it as asked."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class AppLaunch:
    """Open the app on a night's projector (a kiosk), on league `db_path`."""

    projector_night: str | None = None
    db_path: Path | None = None

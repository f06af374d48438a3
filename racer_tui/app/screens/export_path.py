"""Where an export goes: the file name's ending chooses the format (the League screen's
leaderboard and the Nights screen's night both ask for one)."""

from __future__ import annotations

from pathlib import Path

EXPORT_FORMATS = {".csv": "csv", ".json": "json", ".md": "markdown", ".markdown": "markdown"}


def check_export_path(text: str) -> str | None:
    """Why `text` cannot be exported to, or None."""
    suffix = Path(text).suffix.lower()
    if suffix not in EXPORT_FORMATS:
        return "End the file name with .csv, .json or .md to choose the format."
    if not Path(text).expanduser().parent.is_dir():
        return f"The folder {Path(text).expanduser().parent} does not exist; create it first."
    return None

"""Finding the processes a test's reward code may have left behind, by a marker in their
command line (the containment tests share it)."""

from __future__ import annotations

import psutil


def processes_with(marker: str) -> list[psutil.Process]:
    """Live (not zombie) processes whose command line holds `marker`."""
    found = []
    for process in psutil.process_iter(["cmdline", "status"]):
        cmdline = process.info["cmdline"] or []
        if process.info["status"] != psutil.STATUS_ZOMBIE and any(marker in a for a in cmdline):
            found.append(process)
    return found

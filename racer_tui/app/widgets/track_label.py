"""How the app names a track in lists and choosers: the name racers know, short enough for
80 columns.

Official tracks go by their console name ("re:Invent 2018"); the console lists a track's
direction variants under one name, so those carry an arrow (↺ counter-clockwise, ↻
clockwise) that shortening never cuts. Other tracks go by their own name.
"""

from __future__ import annotations

from rich.text import Text

from sim.tracks.catalog import TrackInfo, list_tracks

# A chooser's current value stays on one line in the 36-column setup panes.
CHOOSER_CELLS = 26
_VARIANTS = (("_ccw", " ↺"), ("_cw", " ↻"))


def track_label(info: TrackInfo, cells: int) -> Text:
    """The track's name as racers know it, at most `cells` wide (plain text, never markup)."""
    name = Text(info.console_name or info.name)
    suffix = ""
    if info.console_name:
        suffix = next((mark for end, mark in _VARIANTS if info.name.endswith(end)), "")
    name.truncate(cells - len(suffix), overflow="ellipsis")
    return name + suffix


def track_options(cells: int = CHOOSER_CELLS) -> list[tuple[Text, str]]:
    """(label, track name) for a Select of every track that can be raced, in listing order."""
    return [(track_label(info, cells), info.name) for info in list_tracks() if info.lappable]

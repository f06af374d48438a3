"""The key footer of every screen, compact when the terminal is narrow.

Textual's footer pads each key; at 80 columns that pushes half of a section's keys off
the line. Below `COMPACT_WIDTH` the padding goes, and so does the palette key (the header
shows it too), so most keys stay in sight; every key is also in the help screen and the
command palette.
"""

from __future__ import annotations

from textual import events
from textual.widgets import Footer


class RacerFooter(Footer):
    COMPACT_WIDTH = 110

    def on_resize(self, event: events.Resize) -> None:
        compact = event.size.width < self.COMPACT_WIDTH
        self.compact = compact
        self.show_command_palette = not compact

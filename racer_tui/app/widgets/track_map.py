"""A track drawn in braille: both borders, and the reference driver's racing line."""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive
from textual.widget import Widget

from racer_tui.app.widgets.braille import braille_lines
from sim.tracks.track import Track


class TrackMap(Widget):
    """Shows one track, scaled to the widget, redrawn only when the track or size changes."""

    DEFAULT_CSS = """
    TrackMap {
        height: 1fr;
        min-height: 8;
        color: $text;
    }
    """

    track: reactive[Track | None] = reactive(None)

    def render(self) -> Text:
        track = self.track
        if track is None:
            return Text("Choose a track.", style="dim")
        lines = braille_lines([track.inner, track.outer], self.size.width, self.size.height)
        return Text("\n".join(lines))

"""A small braille line chart for live training figures.

Data may arrive at any rate (an episode every few milliseconds); the chart repaints at a
calm, fixed rate (2 Hz by default) and only when something changed, because redrawing a
chart at the step rate costs a large share of a core.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from rich.segment import Segment
from rich.style import Style
from textual.strip import Strip
from textual.widget import Widget

from racer_tui.app.widgets.braille import braille_char, set_dots, styled_runs

_AXIS_WIDTH = 8
MAX_POINTS = 5000  # older points are dropped: a chart cell cannot show more anyway


@dataclass
class Series:
    label: str
    component: str  # component class that colours it
    values: list[float] = field(default_factory=list)


def running_mean(values: Sequence[float], window: int) -> list[float]:
    """Mean of the last `window` values at each point (shorter at the start)."""
    if not values:
        return []
    data = np.asarray(values, dtype=np.float64)
    sums = np.cumsum(np.concatenate([[0.0], data]))
    idx = np.arange(1, len(data) + 1)
    lo = np.maximum(idx - window, 0)
    means: list[float] = ((sums[idx] - sums[lo]) / (idx - lo)).tolist()
    return means


def format_value(value: float) -> str:
    if not math.isfinite(value):
        return "-"
    if value == 0.0:
        return "0"  # beside "4.0" on the same axis, "0.000" reads as a finer scale
    magnitude = abs(value)
    # Thousands and millions as 21.8k / 1.2M: an axis label has about 6 columns, and
    # "2.18e+04" is both wider and harder to read at a glance.
    for scale, suffix in ((1e6, "M"), (1e3, "k")):
        if magnitude >= 10 * scale:
            scaled = value / scale
            return f"{scaled:.0f}{suffix}" if abs(scaled) >= 100 else f"{scaled:.1f}{suffix}"
    if magnitude >= 100:
        return f"{value:.0f}"
    if magnitude >= 1:
        return f"{value:.1f}"
    return f"{value:.3f}"


class LineChart(Widget):
    """One or two series (for example reward and its running mean) against their index."""

    DEFAULT_CSS = """
    LineChart {
        height: 1fr;
        min-height: 5;
    }
    LineChart > .chart--title { text-style: bold; }
    LineChart > .chart--axis { color: $text-muted; }
    LineChart > .chart--primary { color: $accent; }
    LineChart > .chart--secondary { color: $warning; text-style: bold; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = {
        "chart--title",
        "chart--axis",
        "chart--primary",
        "chart--secondary",
    }

    def __init__(
        self,
        title: str,
        *,
        unit: str = "",
        mean_window: int | None = None,
        refresh_hz: float = 2.0,
        id: str | None = None,
    ) -> None:
        super().__init__(id=id)
        self.title = title
        self.unit = unit
        self.mean_window = mean_window
        self.refresh_hz = refresh_hz
        self.series = [Series(title, "chart--primary")]
        if mean_window:
            self.series.append(Series(f"mean of {mean_window}", "chart--secondary"))
        self._changed = False
        self._lines: list[Strip] | None = None
        self.repaints = 0
        # What the plot says while it has nothing to draw: its owner knows why.
        self.empty_text = "waiting for data…"

    def on_mount(self) -> None:
        self.set_interval(1.0 / self.refresh_hz, self.repaint_if_changed)

    # --- data ------------------------------------------------------------------------

    def extend(self, values: Sequence[float]) -> None:
        """Append values; the chart repaints on its next calm tick."""
        if not values:
            return
        primary = self.series[0].values
        primary.extend(float(v) for v in values)
        del primary[:-MAX_POINTS]
        self._changed = True

    def replace(self, values: Sequence[float]) -> None:
        self.series[0].values = [float(v) for v in values][-MAX_POINTS:]
        self._changed = True

    def say_when_empty(self, text: str) -> None:
        """What the plot says while it has no value to draw (why it is empty)."""
        if text != self.empty_text:
            self.empty_text = text
            self._changed = True

    @property
    def values(self) -> list[float]:
        return self.series[0].values

    def repaint_if_changed(self) -> None:
        """Repaint now if data arrived since the last repaint (the calm timer calls this)."""
        if self._changed:
            self._changed = False
            self._lines = None
            self.refresh()

    def on_resize(self) -> None:
        self._lines = None
        self.refresh()

    # --- drawing ---------------------------------------------------------------------

    def render_line(self, y: int) -> Strip:
        if self._lines is None:
            self._lines = self._draw()
            self.repaints += 1
        if y < len(self._lines):
            return self._lines[y]
        return Strip.blank(self.size.width)

    def _draw(self) -> list[Strip]:
        width, height = self.size.width, self.size.height
        style = {name: self.get_component_rich_style(name) for name in self.COMPONENT_CLASSES}
        primary = self.series[0].values
        if self.mean_window and len(self.series) > 1:
            self.series[1].values = running_mean(primary, self.mean_window)
        title = self._title_text(width)
        lines = [Strip([Segment(title[:width], style["chart--title"])], min(len(title), width))]
        plot_rows, plot_cols = height - 1, width - _AXIS_WIDTH
        if plot_rows < 1 or plot_cols < 2:
            return lines
        finite = [v for s in self.series for v in s.values if math.isfinite(v)]
        if not finite:  # each line of the reason, as many as the plot has rows for
            said = self.empty_text.splitlines()[:plot_rows]
            return [*lines, *(Strip([Segment(line[:width], Style(dim=True))]) for line in said)]
        low, high = min(finite), max(finite)
        if high - low < 1e-9:
            low, high = low - 0.5, high + 0.5
        grids = [
            (self._grid(s.values, plot_cols, plot_rows, low, high), style[s.component])
            for s in self.series
        ]
        for row in range(plot_rows):
            label = ""
            if row == 0:
                label = format_value(high)
            elif row == plot_rows - 1:
                label = format_value(low)
            segments = [
                Segment(
                    label.rjust(_AXIS_WIDTH - 1)[: _AXIS_WIDTH - 1] + "┤"
                    if label
                    else " " * (_AXIS_WIDTH - 1) + "│",
                    style["chart--axis"],
                )
            ]
            cells: list[tuple[str, Style | None]] = []
            for col in range(plot_cols):
                # The later series (the running mean) is drawn over the raw values.
                char, cell_style = " ", None
                for grid, series_style in grids:
                    bits = int(grid[row, col])
                    if bits:
                        char, cell_style = braille_char(bits), series_style
                cells.append((char, cell_style))
            segments.extend(styled_runs(cells))
            lines.append(Strip(segments, width))
        return lines

    def _title_text(self, width: int) -> str:
        """The title with the latest value, and the running mean in the longest wording
        that fits: a chart in a quarter of an 80-column terminal has ~30 columns, at 60x20
        18. The mean goes before the title or the latest value is cut."""
        values = self.series[0].values
        latest = f"{format_value(values[-1]) if values else '-'}{self.unit}"
        text = f"{self.title}: {latest}"
        bare = f"{self.title} {latest}"
        wordings: tuple[str, ...] = (text, bare)
        if self.mean_window and len(self.series) > 1 and self.series[1].values:
            mean = format_value(self.series[1].values[-1])
            wordings = (
                f"{text}  (mean of {self.mean_window}: {mean})",
                f"{text}  (mean {mean})",
                f"{text} ~{mean}",
                f"{bare} ~{mean}",
                *wordings,
            )
        return next((wording for wording in wordings if len(wording) <= width), wordings[-1])

    @staticmethod
    def _grid(values: Sequence[float], cols: int, rows: int, low: float, high: float) -> np.ndarray:
        grid = np.zeros((rows, cols), dtype=np.int32)
        data = np.asarray(values, dtype=np.float64)
        data = data[np.isfinite(data)]
        if len(data) == 0:
            return grid
        dots_w, dots_h = cols * 2, rows * 4
        # Many points per dot column: x spreads them over the width evenly.
        x = np.linspace(0, dots_w - 1, len(data)) if len(data) > 1 else np.zeros(1)
        dx = np.round(x).astype(np.int64)
        dy = np.round((high - data) / (high - low) * (dots_h - 1)).astype(np.int64)
        dy = np.clip(dy, 0, dots_h - 1)
        set_dots(grid, dx, dy)
        return grid

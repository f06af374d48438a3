"""The timekeeper's laps: a header and one line per lap, newest at the bottom, one selected.

Textual's DataTable renders every visible cell again whenever a row is added (its render
caches are keyed by an update count that each `add_row` moves on), and by a 4-minute
heat's last laps that made Capture Lap take up to 56 ms; with this list it takes 9-17 ms
(`python -m benchmarks.app.timekeeper`). A heat has a few dozen laps at most, so this
list keeps each lap's line as text and draws the lines that fit: a new lap costs one line,
and a change of selection never touches the clocks' layout.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from rich.text import Text
from textual import events
from textual.binding import Binding, BindingType
from textual.widget import Widget

# (title, width); a lap's cells are padded to these, the last one is free.
COLUMNS: tuple[tuple[str, int], ...] = (
    ("Lap", 4),
    ("Time", 9),
    ("Raw", 9),
    ("Resets", 7),
    ("Counts", 0),
)
RAW_COLUMN = 2
FULL_WIDTH = sum(width for _, width in COLUMNS) + len("✗ resets")


class LapList(Widget, can_focus=True):
    """Laps as lines under a header; ↑/↓ or a click choose the lap a key acts on
    (`selected`). The header counts the laps above and below the ones that fit."""

    DEFAULT_CSS = """
    LapList { height: 1fr; text-wrap: nowrap; text-overflow: ellipsis; }
    LapList > .lap-list--header { text-style: bold; }
    LapList > .lap-list--selected { background: $block-cursor-background; }
    LapList:focus > .lap-list--selected { text-style: bold; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = {"lap-list--header", "lap-list--selected"}
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("up", "move(-1)", "Previous lap", show=False),
        Binding("down", "move(1)", "Next lap", show=False),
        Binding("home", "move(-1000)", "First lap", show=False),
        Binding("end", "move(1000)", "Last lap", show=False),
    ]

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.lines: list[tuple[tuple[str, ...], Text]] = []  # each lap's cells and verdict
        self.selected: int | None = None
        self.top = 0  # the first lap shown

    def show(self, lines: Sequence[tuple[tuple[str, ...], Text]], *, select_last: bool) -> None:
        """Show these laps; select the newest, or keep the selection where it was."""
        self.lines = list(lines)
        if not self.lines:
            self.selected = None
        elif select_last or self.selected is None:
            self.selected = len(self.lines) - 1
        else:
            self.selected = min(self.selected, len(self.lines) - 1)
        self.refresh()  # its size never depends on the laps: no layout

    def action_move(self, by: int) -> None:
        if self.selected is None:
            return
        self.selected = min(max(self.selected + by, 0), len(self.lines) - 1)
        self.refresh()

    def on_click(self, event: events.Click) -> None:
        index = self.top + event.y - 1  # the header is row 0
        if 0 <= event.y - 1 < self._rows() and index < len(self.lines):
            self.selected = index
            self.refresh()

    def on_mouse_scroll_up(self, event: events.MouseScrollUp) -> None:
        event.stop()
        self.action_move(-1)

    def on_mouse_scroll_down(self, event: events.MouseScrollDown) -> None:
        event.stop()
        self.action_move(1)

    def rows(self) -> list[list[str]]:
        """Every lap's cells as plain text, the verdict last."""
        return [[*cells, verdict.plain] for cells, verdict in self.lines]

    def render(self) -> Text:
        header_style = self.get_component_rich_style("lap-list--header", partial=True)
        selected_style = self.get_component_rich_style("lap-list--selected", partial=True)
        rows = self._rows()
        start = self.top = self._first_shown(rows)
        text = Text(no_wrap=True, overflow="ellipsis")
        # Narrower than every column and a verdict (a match's two lists at 60 columns):
        # the raw time goes, the time with penalties and the verdict stay.
        drop = (RAW_COLUMN,) if self.size.width < FULL_WIDTH else ()
        text.append(_line(tuple(title for title, _ in COLUMNS[:-1]), Text(COLUMNS[-1][0]), drop))
        text.stylize(header_style)
        above, below = start, max(len(self.lines) - start - rows, 0)
        if above or below:  # laps that do not fit: say so, and which way they are
            text.append(f"  ↑{above} ↓{below}", style="dim")
        for index in range(start, min(start + rows, len(self.lines))):
            cells, verdict = self.lines[index]
            line = _line(cells, verdict, drop)
            if index == self.selected:
                line.pad_right(max(self.size.width - line.cell_len, 0))
                line.stylize(selected_style)
            text.append("\n")
            text.append(line)
        return text

    def _rows(self) -> int:
        return max(self.size.height - 1, 0)

    def _first_shown(self, rows: int) -> int:
        """The first lap shown: as before, moved only as far as the selection needs."""
        top = min(self.top, max(len(self.lines) - rows, 0))
        if self.selected is not None and rows:
            top = min(max(top, self.selected - rows + 1), self.selected)
        return max(top, 0)


def _line(cells: tuple[str, ...], last: Text, drop: tuple[int, ...] = ()) -> Text:
    line = Text()
    for index, (cell, (_, width)) in enumerate(zip(cells, COLUMNS, strict=False)):
        if index not in drop:
            line.append(cell.rjust(width - 1) + " ")
    line.append(last)
    return line

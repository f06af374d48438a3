"""Fill a DataTable with widths measured up front, fitted to the table's width.

Textual's DataTable measures new rows on its next idle moment; a table filled and painted
in the same moment paints them at the header's width first ("refere" for "reference
driver"), and the cached rows can stay that way. Setting every column's width from the
content before adding the rows avoids that, and the widths are exact.

A table wider than its room would scroll sideways, and at 80x24 the racer would never see
its right-hand columns. So each column says how it gives way (`Col`): a name column loses
its end ("Alexandra Montgo…") down to a readable width, and the least important columns
collapse, in the order the screen chose, until the rest fits. A `FittedTable` fits itself
again whenever its size changes.

Sections refill their tables each time they are shown (models may have trained since);
filling a table with what it already shows, at the same width, is skipped, so a section
switch costs no table rebuild and the cursor stays where the racer left it.
"""

from __future__ import annotations

import weakref
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

from rich.text import Text
from textual import events
from textual.widgets import DataTable

from sim.foundation.plain_names import look_alike_key

Cell = str | Text


@dataclass(frozen=True)
class Col:
    """A column and how it gives way when the table is too narrow.

    Columns give way in rising `keep` order (of equals, the rightmost first); None never
    gives way. Giving way means losing the end of the text ("Alexandra Montgo…") down to
    `shrink_to` characters when that is set, and then, if the table is still too wide and
    `collapses`, disappearing."""

    label: str
    keep: int | None = None
    shrink_to: int | None = None
    collapses: bool = True
    # A name whose last words in brackets tell it from another ("beginner-oval" and
    # "beginner-oval (physical)") loses the end of what comes before them instead
    # ("begin… (physical)"): two boards never look alike.
    keeps_tail: bool = False
    # A model name tells itself from its siblings at either end ("reinvent-2018-v2" and
    # "reinvent-2018-v3"): it loses its middle ("reinv…8-v3"), never its end.
    cuts_middle: bool = False
    # Names that must never be cut to read as another's ("Alexandra Montgo…" for both
    # Alexandra Montgomery and Alexandra Montgolfier): shrunk no narrower than every cell
    # still reads unlike every other, look-alike letters and all.
    stays_distinct: bool = False


ColumnSpec = str | Col


def _width(cell: Cell) -> int:
    return cell.cell_len if isinstance(cell, Text) else Text(cell).cell_len


def fit_widths(
    natural: Sequence[int],
    columns: Sequence[Col],
    room: int,
    padding: int,
    least: Sequence[int] | None = None,
) -> list[int | None]:
    """Each column's width in the table (None: collapsed) so the whole fits in `room`
    cells, each column also taking `padding` cells on either side. When even the
    essential columns at their narrowest do not fit, they are left as wide as they can be
    (the table then scrolls: better than losing the racer's time)."""
    widths: list[int | None] = list(natural)
    floors = [
        max(_width(col.label), min(col.shrink_to, width)) if col.shrink_to else width
        for col, width in zip(columns, natural, strict=True)
    ]
    if least is not None:  # what a column needs whatever its shrink_to (a tail, names apart)
        floors = [
            min(width, max(floor, need))
            for floor, need, width in zip(floors, least, natural, strict=True)
        ]

    def total() -> int:
        return sum(width + 2 * padding for width in widths if width is not None)

    # The least important first; of equals, the rightmost.
    order = sorted(
        (i for i, col in enumerate(columns) if col.keep is not None),
        key=lambda i: (columns[i].keep or 0, -i),
    )
    for index in order:
        width = widths[index]
        assert width is not None
        excess = total() - room
        if excess <= 0:
            break
        if floors[index] < width:
            widths[index] = width = max(floors[index], width - excess)
        if total() > room and columns[index].collapses:
            widths[index] = None
    # A name shrunk before a later collapse made room gets that room back.
    for index in reversed(order):
        width = widths[index]
        spare = room - total()
        if spare <= 0:
            break
        if width is not None and width < natural[index]:
            widths[index] = min(natural[index], width + spare)
    return widths


def tail_of(cell: Cell) -> str:
    """The words in brackets that end a name, with the space before them ("" if none)."""
    plain = cell.plain if isinstance(cell, Text) else cell
    start = plain.rfind(" (")
    return plain[start:] if start > 0 and plain.endswith(")") else ""


HEAD_LEAST = 3  # what a kept tail leaves before it at least: two letters and "…"


def distinct_width(cells: Sequence[Cell], *, middle: bool = False) -> int:
    """The narrowest width at which the cells, each cut to it (at the end, or in the
    `middle`), still read as different names as they do in full (a reader's eye:
    sim.foundation.plain_names). A wider cut never joins two names a narrower one keeps
    apart, so it is searched by halves."""
    names = {_plain(cell) for cell in cells}
    apart = len({look_alike_key(name) for name in names})

    def reads_apart(width: int) -> bool:
        cut = {look_alike_key(_plain(_shortened(name, width, middle=middle))) for name in names}
        return len(cut) == apart

    low, high = 1, max((_width(name) for name in names), default=1)
    while low < high:
        halfway = (low + high) // 2
        if reads_apart(halfway):
            high = halfway
        else:
            low = halfway + 1
    return high


def _plain(cell: Cell) -> str:
    return cell.plain if isinstance(cell, Text) else cell


def _shortened(cell: Cell, width: int, keeps_tail: bool = False, middle: bool = False) -> Cell:
    if _width(cell) <= width:
        return cell
    text = cell.copy() if isinstance(cell, Text) else Text(cell)
    if middle and width >= 5 and len(text.plain) == _width(text):
        kept_end = (width - 1) // 2  # the end keeps as much as the start, or one less
        kept_start = width - 1 - kept_end
        return Text.assemble(text[:kept_start], "…", text[len(text.plain) - kept_end :])
    tail = tail_of(text) if keeps_tail else ""
    if tail and width >= len(tail) + HEAD_LEAST:
        cut = len(text.plain) - len(tail)
        head, end = text[:cut], text[cut:]
        head.truncate(width - len(tail), overflow="ellipsis")
        return Text.assemble(head, end, justify=text.justify)
    text.truncate(width, overflow="ellipsis")
    return text


def _cell_content(cell: Cell) -> Hashable:
    if isinstance(cell, Text):
        return (
            cell.plain,
            str(cell.style),
            tuple((s.start, s.end, str(s.style)) for s in cell.spans),
        )
    return cell


def _room(table: DataTable[object], row_count: int) -> int | None:
    """Cells across the table for its columns, or None before its first layout."""
    region = table.content_region
    if not region.width:
        return None
    rows_high = row_count + (table.header_height if table.show_header else 0)
    styles = table.styles
    scrolls = styles.scrollbar_gutter == "stable" or (
        styles.overflow_y != "hidden" and rows_high > region.height
    )
    return region.width - (styles.scrollbar_size_vertical if scrolls else 0)


@dataclass(frozen=True)
class _Filling:
    columns: tuple[Col, ...]
    rows: tuple[tuple[Cell, ...], ...]
    keys: tuple[str, ...] | None


# What each table was last filled with and at which widths (tables are never equal to each
# other, so they key a weak dictionary by identity; a table that goes away takes its entry
# with it).
_FILLED: weakref.WeakKeyDictionary[DataTable[object], Hashable] = weakref.WeakKeyDictionary()
_ASKED: weakref.WeakKeyDictionary[DataTable[object], _Filling] = weakref.WeakKeyDictionary()


def fill_table(
    table: DataTable[object],
    columns: Sequence[ColumnSpec],
    rows: Sequence[Sequence[Cell]],
    keys: Sequence[str] | None = None,
) -> None:
    """Replace the table's columns and rows; `keys` names the rows (optional). Each
    column's key is its position in `columns`, so a header click names the column even
    when some collapsed. Nothing happens when the table already shows exactly these."""
    filling = _Filling(
        tuple(Col(spec) if isinstance(spec, str) else spec for spec in columns),
        tuple(tuple(row) for row in rows),
        None if keys is None else tuple(keys),
    )
    _ASKED[table] = filling
    _lay_out(table, filling)


def _least(col: Col, cells: Sequence[Cell]) -> int:
    """What the column needs whatever its `shrink_to` (0: nothing more)."""
    if col.stays_distinct:
        return distinct_width(cells, middle=col.cuts_middle)
    if col.keeps_tail:
        return max((len(tail_of(cell)) + HEAD_LEAST for cell in cells), default=0)
    return 0


def _lay_out(table: DataTable[object], filling: _Filling) -> None:
    natural = [
        max([_width(col.label), *(_width(row[index]) for row in filling.rows)])
        for index, col in enumerate(filling.columns)
    ]
    least = [
        _least(col, [row[index] for row in filling.rows])
        for index, col in enumerate(filling.columns)
    ]
    room = _room(table, len(filling.rows))
    widths: list[int | None] = (
        list(natural)
        if room is None
        else fit_widths(natural, filling.columns, room, table.cell_padding, least)
    )
    content = (
        tuple(widths),
        tuple(col.label for col in filling.columns),
        tuple(tuple(_cell_content(cell) for cell in row) for row in filling.rows),
        filling.keys,
    )
    if _FILLED.get(table) == content and table.row_count == len(filling.rows):
        return
    _FILLED[table] = content
    table.clear(columns=True)
    shown = [index for index, width in enumerate(widths) if width is not None]
    for index in shown:
        width = widths[index]
        table.add_column(filling.columns[index].label, width=width, key=str(index))
    for number, row in enumerate(filling.rows):
        table.add_row(
            *(
                _shortened(
                    row[index],
                    widths[index] or 0,
                    filling.columns[index].keeps_tail,
                    filling.columns[index].cuts_middle,
                )
                for index in shown
            ),
            key=filling.keys[number] if filling.keys is not None else None,
        )


def column_index(event: DataTable.HeaderSelected) -> int:
    """The position in `fill_table`'s `columns` of the header the racer clicked."""
    return int(event.column_key.value or 0)


class FittedTable(DataTable[object]):
    """A DataTable that fits its columns again (see `fill_table`) when its size changes,
    keeping the racer's cursor and scroll where they were. Home and End go to the first and
    last row of a row table, as in any list (Textual's go to the first and last column)."""

    def action_scroll_home(self) -> None:
        if self.cursor_type == "row":
            self.action_scroll_top()
        else:
            super().action_scroll_home()

    def action_scroll_end(self) -> None:
        if self.cursor_type == "row":
            self.action_scroll_bottom()
        else:
            super().action_scroll_end()

    def on_resize(self, event: events.Resize) -> None:
        filling = _ASKED.get(self)
        if filling is None:
            return
        row, column, scroll = self.cursor_row, self.cursor_column, self.scroll_y
        before = _FILLED.get(self)
        _lay_out(self, filling)
        if _FILLED.get(self) is not before:
            self.move_cursor(row=row, column=column, scroll=False)
            self.scroll_to(y=scroll, animate=False)


def shown_columns(table: DataTable[object]) -> set[int]:
    """The positions in `fill_table`'s `columns` of the columns the table shows."""
    return {int(key.value or 0) for key in table.columns}

"""Fill a DataTable with widths measured up front.

Textual's DataTable measures new rows on its next idle moment; a table filled and painted
in the same moment paints them at the header's width first ("refere" for "reference
driver"), and the cached rows can stay that way. Setting every column's width from the
content before adding the rows avoids that, and the widths are exact.

Sections refill their tables each time they are shown (models may have trained since);
filling a table with what it already shows is skipped, so a section switch costs no
table rebuild and the cursor stays where the racer left it.
"""

from __future__ import annotations

import weakref
from collections.abc import Hashable, Sequence

from rich.text import Text
from textual.widgets import DataTable

Cell = str | Text


def _width(cell: Cell) -> int:
    return cell.cell_len if isinstance(cell, Text) else Text(cell).cell_len


# What each table was last filled with (tables are never equal to each other, so they key
# a weak dictionary by identity; a table that goes away takes its entry with it).
_FILLED: weakref.WeakKeyDictionary[DataTable[object], Hashable] = weakref.WeakKeyDictionary()


def _cell_content(cell: Cell) -> Hashable:
    if isinstance(cell, Text):
        return (
            cell.plain,
            str(cell.style),
            tuple((s.start, s.end, str(s.style)) for s in cell.spans),
        )
    return cell


def fill_table(
    table: DataTable[object],
    columns: Sequence[str],
    rows: Sequence[Sequence[Cell]],
    keys: Sequence[str] | None = None,
) -> None:
    """Replace the table's columns and rows; `keys` names the rows (optional). Nothing
    happens when the table already shows exactly these."""
    content = (
        tuple(columns),
        tuple(tuple(_cell_content(cell) for cell in row) for row in rows),
        None if keys is None else tuple(keys),
    )
    if _FILLED.get(table) == content and table.row_count == len(rows):
        return
    _FILLED[table] = content
    table.clear(columns=True)
    for index, label in enumerate(columns):
        width = max([_width(label), *(_width(row[index]) for row in rows)])
        table.add_column(label, width=width)
    for number, row in enumerate(rows):
        table.add_row(*row, key=keys[number] if keys is not None else None)

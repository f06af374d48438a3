"""Fill a DataTable with widths measured up front.

Textual's DataTable measures new rows on its next idle moment; a table filled and painted
in the same moment paints them at the header's width first ("refere" for "reference
driver"), and the cached rows can stay that way. Setting every column's width from the
content before adding the rows avoids that, and the widths are exact.
"""

from __future__ import annotations

from collections.abc import Sequence

from rich.text import Text
from textual.widgets import DataTable

Cell = str | Text


def _width(cell: Cell) -> int:
    return cell.cell_len if isinstance(cell, Text) else Text(cell).cell_len


def fill_table(
    table: DataTable[object],
    columns: Sequence[str],
    rows: Sequence[Sequence[Cell]],
    keys: Sequence[str] | None = None,
) -> None:
    """Replace the table's columns and rows; `keys` names the rows (optional)."""
    table.clear(columns=True)
    for index, label in enumerate(columns):
        width = max([_width(label), *(_width(row[index]) for row in rows)])
        table.add_column(label, width=width)
    for number, row in enumerate(rows):
        table.add_row(*row, key=keys[number] if keys is not None else None)

"""Plot points on a terminal grid with braille characters (2 x 4 dots per cell)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from rich.segment import Segment
from rich.style import Style

# Bit of each dot inside a braille cell, indexed [row][column].
_DOT_BITS = np.array([[0x01, 0x08], [0x02, 0x10], [0x04, 0x20], [0x40, 0x80]], dtype=np.int64)
BRAILLE_BASE = 0x2800


def set_dots(grid: NDArray[np.int32], dx: NDArray[np.int64], dy: NDArray[np.int64]) -> None:
    """Set dots (dot column `dx`, dot row `dy`) in a (rows, columns) grid of braille bits."""
    np.bitwise_or.at(grid, (dy // 4, dx // 2), _DOT_BITS[dy % 4, dx % 2].astype(grid.dtype))


def braille_char(bits: int) -> str:
    return chr(BRAILLE_BASE + bits)


def styled_runs(cells: list[tuple[str, Style | None]]) -> list[Segment]:
    """Segments for a row of (character, style) cells, one segment per run of one style."""
    segments: list[Segment] = []
    text: list[str] = []
    current: Style | None = None
    for char, style in cells:
        if style != current and text:
            segments.append(Segment("".join(text), current))
            text = []
        current = style
        text.append(char)
    if text:
        segments.append(Segment("".join(text), current))
    return segments


def braille_lines(
    polylines: list[NDArray[np.float64]], columns: int, rows: int, *, step: float = 0.0
) -> list[str]:
    """Draw polylines (each (N, 2), world units) scaled to fit `columns` x `rows` cells.

    Aspect ratio is kept: a braille dot is about half as wide as it is tall on screen,
    and a cell is 2 dots wide and 4 tall, so dots are square-ish.
    """
    if columns < 1 or rows < 1 or not polylines:
        return [""] * max(rows, 0)
    dense = [_densify(line, step) for line in polylines if len(line) > 1]
    if not dense:
        return [" " * columns] * rows
    every = np.vstack(dense)
    lo, hi = every.min(axis=0), every.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    dots_w, dots_h = columns * 2, rows * 4
    scale = min((dots_w - 1) / span[0], (dots_h - 1) / span[1])
    grid = np.zeros((rows, columns), dtype=np.int32)
    for line in dense:
        dx = np.round((line[:, 0] - lo[0]) * scale).astype(np.int64)
        # Screen rows grow downwards, world y grows upwards.
        dy = np.round((hi[1] - line[:, 1]) * scale).astype(np.int64)
        dx = np.clip(dx, 0, dots_w - 1)
        dy = np.clip(dy, 0, dots_h - 1)
        set_dots(grid, dx, dy)
    return ["".join(braille_char(int(v)) if v else " " for v in row) for row in grid]


def _densify(line: NDArray[np.float64], step: float) -> NDArray[np.float64]:
    seg = np.hypot(*np.diff(line, axis=0).T)
    total = float(seg.sum())
    spacing = step if step > 0 else max(total / 2000.0, 1e-6)
    count = max(int(total / spacing), 2)
    cumulative = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.linspace(0.0, total, count)
    return np.stack(
        [np.interp(s, cumulative, line[:, 0]), np.interp(s, cumulative, line[:, 1])], axis=1
    )

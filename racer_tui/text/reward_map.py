"""A reward map (sim.reward.map) as terminal text: two map rows per character line (the
upper half block takes one row's colour, its background the next), thinned to fit a
width, with a legend. Given the track, its edges, centre line and start line are drawn
over the colours as dots on the cells they cross, so the colours stay visible behind them.
Rich only, so the headless CLI and the model editor both draw it."""

from __future__ import annotations

import math

import numpy as np
from rich.color import Color
from rich.style import Style
from rich.text import Text

from sim.reward.map import (
    BORDER_COLOUR,
    CENTRE_COLOUR,
    FAILED_COLOUR,
    START_COLOUR,
    RewardMap,
    colour,
    pixel_rows,
    polyline_samples,
    start_line,
)
from sim.tracks.track import Track

# What is drawn over the colours, later ones over earlier ones where they cross a cell.
_EDGE = ("•", BORDER_COLOUR)
_CENTRE = ("·", CENTRE_COLOUR)
_START = ("■", START_COLOUR)


def _rgb(rgb: tuple[int, int, int]) -> Color:
    return Color.from_rgb(*rgb)


# Terminal cells are about twice as tall as wide: one character shows two map rows.
_HALF_BLOCK = "▀"


def _marks(
    reward_map: RewardMap, track: Track, scale: float
) -> dict[tuple[int, int], tuple[str, tuple[int, int, int]]]:
    """(text line, column) -> the glyph and colour of the track line crossing that cell."""
    spacing = reward_map.options.spacing
    origin_x, origin_y = reward_map.origin
    rows = len(reward_map.values)
    marks: dict[tuple[int, int], tuple[str, tuple[int, int, int]]] = {}
    for line, mark in (
        (track.center, _CENTRE),
        (track.inner, _EDGE),  # where a shown cell holds both, the road's edge matters more
        (track.outer, _EDGE),
        (start_line(track), _START),
    ):
        xy = polyline_samples(line, spacing * scale / 2)
        column = np.floor(np.round((xy[:, 0] - origin_x) / spacing) / scale).astype(int)
        row_from_top = rows - 1 - np.round((xy[:, 1] - origin_y) / spacing)
        line_index = np.floor(row_from_top / scale).astype(int) // 2
        for key in zip(line_index.tolist(), column.tolist(), strict=True):
            marks[key] = mark
    return marks


def _mix(a: tuple[int, int, int], b: tuple[int, int, int]) -> tuple[int, int, int]:
    return (a[0] + b[0]) // 2, (a[1] + b[1]) // 2, (a[2] + b[2]) // 2


def map_text(
    reward_map: RewardMap, width: int, *, legend: bool = True, track: Track | None = None
) -> Text:
    """Two map rows per line, a cell per character, thinned to fit `width` columns (each
    shown cell is the map's cell at its top-left corner: `scale` map cells apart, a
    fraction, so the map fills the width); with `track`, its lines drawn over the colours."""
    rows = pixel_rows(reward_map)
    columns = len(rows[0]) if rows else 0
    scale = max(1.0, columns / max(20, width - 1))
    kept_columns = [int(i * scale) for i in range(math.floor(columns / scale))]
    kept_rows = [int(i * scale) for i in range(math.floor(len(rows) / scale))]
    thinned = [[rows[r][c] for c in kept_columns] for r in kept_rows]
    marks = _marks(reward_map, track, scale) if track is not None else {}
    text = Text()
    for line_index, (upper, lower) in enumerate(
        zip(thinned[::2], [*thinned[1::2], []], strict=False)
    ):
        for index, top in enumerate(upper):
            bottom = lower[index] if index < len(lower) else (0, 0, 0)
            mark = marks.get((line_index, index))
            if mark is None:
                text.append(_HALF_BLOCK, style=Style(color=_rgb(top), bgcolor=_rgb(bottom)))
            else:
                glyph, rgb = mark
                behind = _rgb(_mix(top, bottom))
                text.append(glyph, style=Style(color=_rgb(rgb), bgcolor=behind, bold=True))
        text.append("\n")
    if not legend:
        return text
    shown = reward_map.shown
    low, high = (min(shown), max(shown)) if shown else (0.0, 0.0)
    text.append("low ")
    for fraction in (0.0, 0.25, 0.5, 0.75, 1.0):
        text.append("██", style=Style(color=_rgb(colour(fraction))))
    text.append(f" high: {low:.4g} to {high:.4g} on {reward_map.track}")
    heading = reward_map.options.heading
    facing = "along the track" if heading is None else f"facing {heading:g}°"
    text.append(f", at {reward_map.options.speed:g} m/s {facing}")
    text.append(f", {reward_map.options.spacing * scale:.2g} m per cell")
    if reward_map.failed:
        text.append(" · ")
        text.append("██", style=Style(color=_rgb(FAILED_COLOUR)))
        text.append(" failed")
    if track is not None:
        for (glyph, rgb), meaning in (
            (_EDGE, "road edges"),
            (_CENTRE, "centre line"),
            (_START, "start"),
        ):
            text.append("  ")
            text.append(glyph, style=Style(color=_rgb(rgb), bold=True))
            text.append(f" {meaning}")
    return text

"""A reward map (sim.reward_map) as terminal text: two map rows per character line (the
upper half block takes one row's colour, its background the next), thinned to fit a
width, with a legend. Rich only, so the headless CLI and the model editor both draw it."""

from __future__ import annotations

import math

from rich.color import Color
from rich.style import Style
from rich.text import Text

from sim.reward_map import FAILED_COLOUR, RewardMap, colour, pixel_rows


def _rgb(rgb: tuple[int, int, int]) -> Color:
    return Color.from_rgb(*rgb)


# Terminal cells are about twice as tall as wide: one character shows two map rows.
_HALF_BLOCK = "▀"


def map_text(reward_map: RewardMap, width: int, *, legend: bool = True) -> Text:
    """Two map rows per line, a cell per character, thinned to fit `width` columns."""
    rows = pixel_rows(reward_map)
    columns = len(rows[0]) if rows else 0
    step = max(1, math.ceil(columns / max(20, width - 1)))
    thinned = [row[::step] for row in rows[::step]]
    text = Text()
    for upper, lower in zip(thinned[::2], [*thinned[1::2], []], strict=False):
        for index, top in enumerate(upper):
            bottom = lower[index] if index < len(lower) else (0, 0, 0)
            text.append(_HALF_BLOCK, style=Style(color=_rgb(top), bgcolor=_rgb(bottom)))
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
    text.append(f", {reward_map.options.spacing * step:g} m per cell")
    if reward_map.failed:
        text.append(" · ")
        text.append("██", style=Style(color=_rgb(FAILED_COLOUR)))
        text.append(" failed")
    return text

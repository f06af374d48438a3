"""What a reward function pays along a lap (sim.reward.lap) as a terminal chart: a row per
line and speed, each step's reward drawn as a bar from start to finish on one shared scale,
and the lap's total at its end. Rich only, so the headless CLI and the app can both draw it."""

from __future__ import annotations

import itertools
import math

from rich.text import Text

from sim.reward.lap import CENTRE_LINE, LapPay

_BARS = " ▁▂▃▄▅▆▇█"  # nothing, then eighths of a cell
_LINE_STYLES = {CENTRE_LINE: "cyan"}
_OTHER_LINE_STYLE = "magenta"
_TOTAL_WIDTH = 12


def _binned(rewards: tuple[float, ...], bins: int) -> list[float]:
    """The mean reward of each of `bins` equal stretches of the lap (fewer steps: each)."""
    if len(rewards) <= bins:
        return list(rewards)
    edges = [round(i * len(rewards) / bins) for i in range(bins + 1)]
    return [
        math.fsum(rewards[start:end]) / (end - start)
        for start, end in itertools.pairwise(edges)
        if end > start
    ]


def lap_chart(pays: list[LapPay], width: int) -> Text:
    """The chart, `width` columns wide (at least 40)."""
    width = max(40, width)
    label_width = max(len(f"{pay.line} {pay.speed:g} m/s ") for pay in pays)
    bins = width - label_width - _TOTAL_WIDTH
    rows = [_binned(pay.rewards, bins) for pay in pays]
    shown = [value for row in rows for value in row]
    low = min(0.0, *shown) if shown else 0.0
    high = max(shown) if shown else 1.0
    span = high - low or 1.0
    text = Text()
    text.append(f"reward per step, start to finish, {low:.3g} to {high:.3g}", style="dim")
    text.append(" " * max(1, width - _TOTAL_WIDTH - len(text.plain)))
    text.append(f"{'per lap':>{_TOTAL_WIDTH}}\n", style="dim")
    previous_line = None
    for pay, row in zip(pays, rows, strict=True):
        style = _LINE_STYLES.get(pay.line, _OTHER_LINE_STYLE)
        name = pay.line if pay.line != previous_line else ""
        previous_line = pay.line
        text.append(f"{name:<{label_width - len(f' {pay.speed:g} m/s ')}}", style=style)
        text.append(f" {pay.speed:g} m/s", style="bold")
        text.append(" ")
        bars = "".join(_BARS[round((value - low) / span * (len(_BARS) - 1))] for value in row)
        text.append(f"{bars:<{bins}}", style=style)
        text.append(f"{pay.total:>{_TOTAL_WIDTH}.4g}\n")
    return text

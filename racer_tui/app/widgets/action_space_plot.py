"""A small picture of an action space: steering across, speed up.

Like the DeepRacer console's action space graph, left turns are on the left (DeepRacer's
positive steering angles), so the picture reads like the car's view of the road. Discrete
actions are dots; a continuous space is the shaded rectangle of its ranges.
"""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive
from textual.widget import Widget

from sim.deepracer.action_space import ActionSpace
from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING

_AXIS = 5  # "4.0 ┤"
_DOT = "●"
_SHADE = "▒"


def action_space_picture(space: ActionSpace | None, width: int, height: int) -> Text:
    """The picture in `width` x `height` cells (at least 16 x 5 to show anything)."""
    columns, rows = width - _AXIS, height - 2
    if space is None or columns < 11 or rows < 3:
        return Text("")
    grid = [[" "] * columns for _ in range(rows)]

    def column(steering: float) -> int:
        return round((MAX_STEERING - steering) / (2 * MAX_STEERING) * (columns - 1))

    def row(speed: float) -> int:
        return round((1.0 - speed / MAX_SPEED) * (rows - 1))

    if space.kind == "discrete":
        for action in space.actions:
            grid[row(action.speed)][column(action.steering_angle)] = _DOT
    else:
        (steer_low, steer_high), (speed_low, speed_high) = space.steering_range, space.speed_range
        for r in range(row(speed_high), row(speed_low) + 1):
            for c in range(column(steer_high), column(steer_low) + 1):
                grid[r][c] = _SHADE
    text = Text(no_wrap=True, overflow="crop")
    labelled = {0: f"{MAX_SPEED:g}", rows // 2: f"{MAX_SPEED / 2:g}", rows - 1: "0"}
    for r, cells in enumerate(grid):
        label = labelled.get(r, "")
        text.append(f"{label:>3} {'┤' if label else '│'}", style="dim")
        text.append("".join(cells), style="bold" if space.kind == "discrete" else "")
        text.append("\n")
    text.append(" " * (_AXIS - 1) + "└" + "─" * columns + "\n", style="dim")
    left, middle, right = f"{MAX_STEERING:g}° left", "0°", f"right {MAX_STEERING:g}°"
    gap = columns - len(left) - len(right)
    if gap >= len(middle) + 2:
        before = (columns - len(middle)) // 2 - len(left)
        scale = left + " " * before + middle + " " * (gap - before - len(middle)) + right
    else:
        scale = left + " " * max(gap, 1) + right
    text.append(" " * _AXIS + scale, style="dim")
    return text


class ActionSpacePlot(Widget):
    """`space` redrawn to fit the widget; speed in m/s up, steering in degrees across."""

    DEFAULT_CSS = """
    ActionSpacePlot {
        height: 9;
        min-width: 24;
        color: $accent;
    }
    """

    space: reactive[ActionSpace | None] = reactive(None)

    def render(self) -> Text:
        return action_space_picture(self.space, self.size.width, self.size.height)

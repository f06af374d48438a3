"""The reward function templates racer-tui ships (`sim/reward/templates/`, DeepRacer's
sample functions and racer-tui's racing line), as files: their names, their text as
shipped, and which template a model's reward function is.

The racing_line template's copy in a model holds its track's line, written by
`sim.coach.reward_line` (which also gives a template's text with that line).
"""

from __future__ import annotations

import functools
import re
from importlib import resources

from sim.reward.errors import RewardFunctionError

TEMPLATES: dict[str, str] = {
    "follow_center_line": "follow_center_line.py",
    "stay_inside_borders": "stay_inside_borders.py",
    "prevent_zigzag": "prevent_zigzag.py",
    "object_avoidance": "object_avoidance.py",
    "racing_line": "racing_line.py",
}
# The template whose copy in a model holds the line of the model's track (sim.coach): the
# shipped file's empty list is replaced by the comment and list `sim.coach.reward_line`
# writes, matched exactly by `_WRITTEN_LINE` (a line of any other shape is the racer's).
RACING_LINE_TEMPLATE = "racing_line"
EMPTY_LINE = "RACING_LINE = []"
_WRITTEN_LINE = re.compile(
    r"^# The limit lap's line on [^\n]*\n(?:# [^\n]*\n)?"
    r"RACING_LINE = \[\n(?:    \[[^\n]*\],\n)*\]$",
    re.M,
)


def shipped_template(name: str) -> str:
    """A template's text as shipped (the racing line's list empty)."""
    try:
        file_name = TEMPLATES[name]
    except KeyError:
        raise RewardFunctionError(
            name,
            "is not a reward function template",
            advice=f"choose one of {', '.join(TEMPLATES)}",
        ) from None
    return _template_text(file_name)


@functools.cache
def _template_text(file_name: str) -> str:
    """A template file as shipped (read once: the garage compares every model's reward
    function with all of them)."""
    return resources.files("sim.reward.templates").joinpath(file_name).read_text(encoding="utf-8")


def template_name(source: str) -> str | None:
    """Which template `source` is, unchanged (racing_line with a line racer-tui wrote for
    any track), or None."""
    for name, file_name in TEMPLATES.items():
        text = _template_text(file_name)
        compared = source
        if name == RACING_LINE_TEMPLATE:
            compared = _WRITTEN_LINE.sub(EMPTY_LINE, source, count=1)
        if compared == text:
            return name
    return None

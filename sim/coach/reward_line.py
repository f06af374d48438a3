"""The limit lap's line as a reward function reads it, and the `racing_line` template with a
track's line written in.

A reward function compares the car with the line through DeepRacer's params, and its
`speed` is the *commanded* speed (the action's), not the speed driven: the car settles at
`speed_gain` times what it is told. So each row is [x, y, speed to command], the limit lap's
speed divided by the gain and kept inside the action space's speeds, and the same rows go to
`racer-tui tracks line` and into a model's reward function.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from sim.coach.limit_lap import LimitLap, limit_lap
from sim.deepracer.action_space import ActionSpace
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.reward.function import RewardFunction, load_reward_source
from sim.reward.template_files import (
    EMPTY_LINE,
    RACING_LINE_TEMPLATE,
    TEMPLATES,
    shipped_template,
    template_name,
)
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track
from sim.tracks.track import Track, TrackError

# Metres between the points written into a reward function: a scan of a lap's points runs on
# every step, and the function measures the distance to the segment between points, so 0.2 m
# loses nothing a car can drive.
REWARD_SPACING: Final = 0.2


def command_rows(
    lap: LimitLap, every: float, car: CarSpec = DEEPRACER_CAR, space: ActionSpace | None = None
) -> list[list[float]]:
    """The line every `every` metres as [x, y, speed to command] rows, rounded for people."""
    points, speeds = lap.resampled(every)
    low, high = (car.min_speed, car.max_speed)
    if space is not None:
        low, high = min(space.speeds()), space.max_speed
    commands = np.clip(speeds / car.speed_gain, low, high)
    return [
        [round(float(x), 4), round(float(y), 4), round(float(v), 3)]
        for (x, y), v in zip(points, commands, strict=True)
    ]


def python_line(rows: list[list[float]], comment: str) -> str:
    """`RACING_LINE = [...]` as a reward function pastes it, under `comment` (# lines)."""
    body = "".join(f"    {row},\n" for row in rows)
    said = "".join(f"# {line}\n" for line in comment.splitlines())
    return f"{said}RACING_LINE = [\n{body}]"


def line_comment(lap: LimitLap, every: float) -> str:
    """Two lines, each short enough for an editor 80 columns wide."""
    return (
        f"The limit lap's line on {lap.track_name} ({lap.limits}):\n"
        f"[x, y, speed to command m/s] every {every:g} m; a flying lap of "
        f"{lap.flying_seconds:.3f} s."
    )


def with_track_line(template: str, track: Track, space: ActionSpace | None = None) -> str:
    """The racing_line template with `track`'s line (within `space`'s actions) written in."""
    lap = limit_lap(track, space=space)
    rows = command_rows(lap, REWARD_SPACING, space=space)
    line = python_line(rows, line_comment(lap, REWARD_SPACING))
    if EMPTY_LINE not in template:
        raise ValueError("the racing_line template has lost its RACING_LINE = [] line")
    return template.replace(f"\n{EMPTY_LINE}\n", f"\n{line}\n", 1)


def line_followed(
    source: str,
    was: tuple[str, ActionSpace | None],
    now: tuple[str, ActionSpace | None],
) -> str:
    """`source` with its line redrawn for track and actions `now`, when it is the racing_line
    template exactly as written for `was` (a line the racer changed is theirs, and kept)."""

    if was == now or template_name(source) != RACING_LINE_TEMPLATE:
        return source
    try:
        if source != template_source(RACING_LINE_TEMPLATE, *was):
            return source
        return template_source(RACING_LINE_TEMPLATE, *now)
    except TrackError:
        return source  # a track that no longer resolves: the function stays as it was


def template_source(name: str, track: str | None = None, space: ActionSpace | None = None) -> str:
    """The text of one of the reward templates (see `TEMPLATES`). The racing_line template
    comes with the line of `track` (default: reinvent_base) within `space`'s actions."""
    text = shipped_template(name)
    if name != RACING_LINE_TEMPLATE:
        return text
    return with_track_line(text, resolve_track(track or DEFAULT_TRACK), space)


def load_template(name: str) -> RewardFunction:
    """Load one of AWS DeepRacer's sample reward functions, named like its file."""
    return load_reward_source(template_source(name), TEMPLATES[name])

"""Getting faster with the coach: the racing_line reward template with the line of the
model's track, and an action space clustered from the line."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from sim.coach.limit_lap import limit_lap
from sim.coach.line_actions import LineActionsError, actions_from_line
from sim.coach.reward_line import REWARD_SPACING, command_rows, template_source
from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.garage.folder import ModelError, open_model
from sim.garage.options import model_spec, new_model
from sim.garage.overview import reward_origin
from sim.reward.errors import RewardFunctionError
from sim.reward.function import load_reward_source
from sim.reward.sample_params import sample_params
from sim.reward.template_files import template_name
from sim.tracks.catalog import resolve_track

TRACK = "reinvent_base"


def params_on_the_line(index: int, speed: float, aside: float = 0.0) -> dict[str, object]:
    """DeepRacer params for a car at point `index` of reinvent_base's reward line, `aside`
    metres to the left of it, commanding `speed`."""
    rows = command_rows(limit_lap(resolve_track(TRACK)), REWARD_SPACING)
    x, y, _ = rows[index]
    nx, ny, _ = rows[index + 1]
    heading = math.atan2(ny - y, nx - x)
    return {
        **sample_params(objects=()),
        "x": x - aside * math.sin(heading),
        "y": y + aside * math.cos(heading),
        "speed": speed,
        "track_width": 1.07,
    }


def test_the_reward_line_gives_the_speed_to_command_within_the_cars_speeds() -> None:
    lap = limit_lap(resolve_track(TRACK))
    rows = command_rows(lap, REWARD_SPACING)
    speeds = np.array([row[2] for row in rows])
    # The limit lap's speeds are as driven; the car drives 1.02x what it is told.
    assert speeds.max() == pytest.approx(MAX_SPEED)
    assert speeds.min() >= MIN_SPEED and speeds.min() < 0.8 * speeds.max()
    steps = np.hypot(*np.diff(np.array([row[:2] for row in rows]), axis=0).T)
    assert steps == pytest.approx(REWARD_SPACING, abs=0.02)


def test_the_racing_line_template_pays_for_the_line_and_its_speed() -> None:
    reward = load_reward_source(template_source("racing_line", TRACK), "racing_line.py")
    rows = command_rows(limit_lap(resolve_track(TRACK)), REWARD_SPACING)
    index = int(np.argmin([row[2] for row in rows]))  # the slowest point, in a corner
    target = rows[index][2]
    on_line = reward(params_on_the_line(index, target))
    # In proportion to the speed (of the console's 4 m/s), so a slow lap's extra steps
    # do not pay more than a fast lap's.
    assert on_line == pytest.approx(0.001 + target / 4.0, abs=0.01)
    assert reward(params_on_the_line(index, target, aside=0.2)) < on_line
    assert reward(params_on_the_line(index, target, aside=0.6)) == pytest.approx(0.001)
    assert reward(params_on_the_line(index, target + 0.5)) < on_line
    crawling = reward(params_on_the_line(index, 0.5))
    assert crawling * target / 0.5 < on_line  # per metre, crawling on the line pays less
    off = {**params_on_the_line(index, target), "is_offtrack": True}
    assert reward(off) == pytest.approx(0.001)


def test_the_line_is_the_models_track_and_is_recognised_on_any_track() -> None:
    spain = template_source("racing_line", "Spain_track")
    assert "The limit lap's line on Spain_track" in spain
    assert spain != template_source("racing_line", TRACK)
    assert template_name(spain) == "racing_line"
    assert template_name(spain.replace("SPEED_REACH = 1.0", "SPEED_REACH = 2.0")) is None


def test_the_template_pasted_without_a_line_says_where_to_get_one() -> None:
    from importlib import resources

    bare = resources.files("sim.reward.templates").joinpath("racing_line.py").read_text()
    reward = load_reward_source(bare, "racing_line.py")
    with pytest.raises(RewardFunctionError, match="racer-tui tracks line TRACK --python"):
        reward(sample_params())


def test_an_action_space_from_the_line_covers_its_corners_and_straights() -> None:
    space = actions_from_line(resolve_track(TRACK), 10)
    assert space.kind == "discrete" and 8 <= len(space.actions) <= 10
    steering = [a.steering_angle for a in space.actions]
    speeds = [a.speed for a in space.actions]
    assert all(-MAX_STEERING <= s <= MAX_STEERING for s in steering)
    assert all(MIN_SPEED <= v <= MAX_SPEED for v in speeds)
    assert min(steering) < -5.0 and max(steering) > 15.0  # both ways; its corners turn left
    assert max(speeds) > 3.5 and min(speeds) < 3.0
    assert actions_from_line(resolve_track(TRACK), 10) == space  # the same every time
    assert len(actions_from_line(resolve_track(TRACK), 5).actions) <= 5
    with pytest.raises(LineActionsError, match="from 3 to 30"):
        actions_from_line(resolve_track(TRACK), 2)


def test_a_new_model_takes_its_actions_and_reward_from_its_tracks_line() -> None:
    folder = new_model("liner", track="Spain_track", actions_from_line=8, reward="racing_line")
    space = folder.metadata().action_space
    assert space.kind == "discrete" and len(space.actions) <= 8
    source = folder.reward_source()
    assert "The limit lap's line on Spain_track (the action space)" in source
    assert reward_origin(open_model("liner")) == "template racing_line"
    # Moved to another track, the racing_line reward follows it; a racer's own is kept.
    on_spain = model_spec(track="Spain_track", reward="racing_line")
    moved = model_spec(on_spain, track=TRACK)
    assert f"The limit lap's line on {TRACK}" in moved.reward_source
    own_point = on_spain.reward_source.replace(
        "RACING_LINE = [\n", "RACING_LINE = [\n    [0.0, 0.0, 1.0],\n"
    )
    theirs = replace(on_spain, reward_source=own_point)
    assert model_spec(theirs, track=TRACK).reward_source == theirs.reward_source
    with pytest.raises(ModelError, match="not --continuous and --actions-from-line"):
        model_spec(actions_from_line=10, continuous=True)

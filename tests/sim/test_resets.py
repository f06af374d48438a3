"""Where DeepRacer puts a car back, and what a reset costs by default."""

from __future__ import annotations

import math

import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.resets import ResetRules, ResetRulesError, reset_pose
from tests.sim.shapes import HALF, rectangle_track


@pytest.mark.parametrize(("car_y", "lane_y"), [(-0.5, -HALF / 2), (0.3, HALF / 2)])
def test_a_car_goes_back_on_the_lane_nearer_to_where_it_was(car_y: float, lane_y: float) -> None:
    # The rectangle's bottom side runs along +x: inner border at y = +0.38, outer at -0.38.
    x, y, yaw = reset_pose(rectangle_track(), 2.3, 2.2, car_y)
    assert (x, y) == pytest.approx((2.3, lane_y))
    assert yaw == pytest.approx(0.0)


def test_on_a_waypoint_it_points_at_the_next_one() -> None:
    # Up the right side (x = 6): the outer lane runs at x = 6.19 from (6.19, 0.5) upwards.
    x, y, yaw = reset_pose(rectangle_track(), 6.5, 6.5, 0.5)
    assert (x, y) == pytest.approx((6.0 + HALF / 2, 0.5))
    assert yaw == pytest.approx(math.pi / 2)


def test_penalties_follow_simapp_evaluation_defaults() -> None:
    rules = ResetRules(number_of_resets=3)
    assert rules.penalty(EpisodeStatus.OFF_TRACK) == 2.0
    assert rules.penalty(EpisodeStatus.REVERSED) == 2.0  # no reverse penalty of its own
    assert rules.penalty(EpisodeStatus.CRASHED) == 5.0
    assert rules.penalty(EpisodeStatus.IMMOBILIZED) == 0.0
    assert ResetRules(reverse_penalty=1.0).penalty(EpisodeStatus.REVERSED) == 1.0
    assert ResetRules().number_of_resets == 0  # as in training: the first off-track ends it


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"number_of_resets": 1}, "must be 0 or from 2 to 10000, not 1"),
        ({"number_of_resets": 2.5}, "must be a whole number"),
        ({"off_track_penalty": -1.0}, "off_track_penalty must be between 0 and 60 seconds"),
    ],
)
def test_unusable_settings_are_one_sentence(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ResetRulesError, match=message) as caught:
        ResetRules(**kwargs)  # type: ignore[arg-type]
    text = str(caught.value)
    assert text.endswith(".") and "\n" not in text

"""A race's rules carry DeepRacer's race type: presets for league nights, the stored form
of a time trial's rules unchanged, and every value checked in one sentence."""

from __future__ import annotations

import pytest

from sim.physics.objects.settings import RaceType
from sim.race.rules import (
    DEFAULT_RULES,
    RaceRules,
    RulesError,
    preset_rules,
    rules_from_mapping,
)


def test_a_time_trials_rules_keep_their_stored_form() -> None:
    assert "race_type" not in DEFAULT_RULES.to_dict()
    assert "obstacles" not in DEFAULT_RULES.to_dict()
    assert rules_from_mapping(DEFAULT_RULES.to_dict()) == DEFAULT_RULES


@pytest.mark.parametrize("preset", ["object-avoidance", "head-to-bot"])
def test_the_race_type_presets_round_trip(preset: str) -> None:
    rules = preset_rules(preset)
    assert rules.race_type is not RaceType.TIME_TRIAL
    assert rules_from_mapping(rules.to_dict()) == rules
    assert rules.race_words in rules.describe()


def test_a_race_types_own_keys_take_its_defaults_and_are_checked() -> None:
    boxes = rules_from_mapping({"race_type": "object-avoidance"})
    assert boxes.obstacles == 3 and boxes.race_settings.obstacles.count == 3
    bots = rules_from_mapping({"race_type": "HEAD_TO_BOT", "bots": 2, "bot_speed": 0.5})
    assert bots.race_settings.bots.count == 2 and bots.race_settings.bots.speed == 0.5
    with pytest.raises(RulesError, match="obstacles must be a whole number from 1 to 10"):
        rules_from_mapping({"race_type": "object_avoidance", "obstacles": 11})
    with pytest.raises(RulesError, match="race_type must be one of"):
        rules_from_mapping({"race_type": "drag race"})
    with pytest.raises(RulesError, match="bot_speed must be a number of m/s"):
        rules_from_mapping({"race_type": "head_to_bot", "bot_speed": 9})
    # A key of another race type is refused, not dropped without a word.
    with pytest.raises(RulesError, match="obstacles is for object avoidance races"):
        rules_from_mapping({"obstacles": 3})
    with pytest.raises(RulesError, match="needs bots from 1 to 6"):
        RaceRules(race_type=RaceType.HEAD_TO_BOT)

"""DeepRacer on AWS's verdict on reward functions: its validator's rules, in its words."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim.coach.reward_line import template_source
from sim.reward.droa_check import droa_verdict
from sim.reward.droa_rules import (
    TEST_FAILURE,
    route_of,
    static_reasons,
    synthetic_states,
)
from sim.reward.template_files import TEMPLATES

TRACK = "reinvent_base"

ACCEPTED = """\
import math


def reward_function(params):
    if params["all_wheels_on_track"]:
        return float(math.exp(-params["distance_from_center"]))
    return 1e-3
"""


def verdict(source: str, track: str = TRACK) -> list[tuple[str, str, int | None]]:
    found = droa_verdict(source, "reward_function.py", track)
    return [(reason.kind, reason.message.strip(), reason.line) for reason in found.reasons]


def test_a_clean_function_is_accepted() -> None:
    assert verdict(ACCEPTED) == []


def test_an_int_return_is_refused() -> None:
    source = "def reward_function(params):\n    return 1\n"
    assert verdict(source) == [(TEST_FAILURE, "Method returned non-floating type value: 1", None)]


def test_a_forbidden_substring_in_a_comment_is_refused() -> None:
    source = "# a reward I will download later\ndef reward_function(params):\n    return 1.0\n"
    assert verdict(source) == [
        (
            TEST_FAILURE,
            'Your code snippet contains a restricted string "load" that is not allowed. '
            "Please remove or replace the string and try again.",
            1,
        ),
    ]


def test_flake8_s_blank_lines_count_as_droa_runs_it() -> None:
    source = "import math\n\ndef reward_function(params):\n    return math.pi\n"
    assert verdict(source) == [("E302", "expected 2 blank lines, found 1", 3)]


def test_an_illegal_import_is_refused() -> None:
    source = "import os\n\n\ndef reward_function(params):\n    return float(len(os.sep))\n"
    assert verdict(source) == [
        (TEST_FAILURE, "The reward function contains illegal import(s): ['os']", 1)
    ]


def test_an_unused_import_is_flake8_s_f401() -> None:
    source = "import math\n\n\ndef reward_function(params):\n    return 1.0\n"
    assert verdict(source) == [("F401", "'math' imported but unused", 1)]


def test_a_key_droa_s_test_states_lack_is_refused() -> None:
    source = "def reward_function(params):\n    return float(params['projection_distance'])\n"
    assert verdict(source) == [
        (TEST_FAILURE, "Unsafe builtin function detected: \"'projection_distance'\".", 2)
    ]


def test_an_import_inside_the_function_is_refused() -> None:
    source = "def reward_function(params):\n    import math\n    return math.pi\n"
    [(kind, message, line)] = verdict(source)
    assert kind == TEST_FAILURE and line == 2
    assert message == (
        'Unsafe builtin function detected: "{"message": "Import should be put at the top '
        'of file, module: math", "type": "IMPORT_ERROR"}".'
    )


def test_a_call_on_a_literal_fails_droa_s_own_walk() -> None:
    # DRoA's walk over calls cannot name "{}".format and fails with Python's words.
    source = 'def reward_function(params):\n    return float("{}".format(1))\n'
    assert verdict(source) == [(TEST_FAILURE, "can only join an iterable", 2)]


def test_forbidden_builtins_are_listed() -> None:
    source = "def reward_function(params):\n    return float(eval('1'))\n"
    assert verdict(source) == [
        (TEST_FAILURE, "The reward function contains forbidden builtins: ['eval']", 2)
    ]


def test_two_parameters_are_refused() -> None:
    source = "def reward_function(params, more=1):\n    return 1.0\n"
    assert verdict(source) == [
        (
            TEST_FAILURE,
            "Invalid reward function signature. Should be def reward_function(params)",
            None,
        )
    ]


def test_a_reward_out_of_range_on_the_finish_state_is_refused() -> None:
    source = (
        "def reward_function(params):\n"
        "    if params['progress'] == 100:\n"
        "        return 1e6\n"
        "    return 1.0\n"
    )
    assert verdict(source) == [
        (TEST_FAILURE, "Vehicle failed to make it to end of track. Reward: 1000000.0", None)
    ]


def test_a_syntax_error_is_reported_as_droa_parses_flake8() -> None:
    source = "def reward_function(params)\n    return 1.0\n"
    [(kind, message, line)] = verdict(source)
    assert (kind, line) == ("SyntaxError", 1)
    assert "expected ':'" in message


def test_a_function_too_long_for_droa_is_refused_unread() -> None:
    source = ACCEPTED + "#" * 140_001 + "\n"
    [reason] = static_reasons(source)
    assert reason.kind == "SIZE" and "140,000" in reason.message


def test_an_import_error_at_the_top_is_an_import_error() -> None:
    source = "import numpy.nowhere\n\n\ndef reward_function(params):\n    return 1.0\n"
    reasons = verdict(source)
    assert reasons[0][0] == "F401"
    assert reasons[-1][0] == TEST_FAILURE  # the module cannot load: DRoA's import fails


@pytest.mark.parametrize("template", sorted(TEMPLATES))
def test_every_template_passes_droa_s_validator(template: str) -> None:
    # As a model gets it: the racing line template with its track's line filled in.
    assert verdict(template_source(template, TRACK)) == []


def test_the_synthetic_states_are_droa_s() -> None:
    route = route_of("2022_april_open_ccw")
    states = synthetic_states(route)
    assert len(states) == 5
    for state in states:
        assert "projection_distance" not in state
        assert "objects_distance_from_center" not in state
        assert isinstance(state["waypoints"], np.ndarray)
        assert state["waypoints"].shape == (len(route), 2)
    assert states[3]["all_wheels_on_track"] is False and states[3]["speed"] == 1
    assert states[4]["speed"] == 5.0 and states[4]["progress"] == 100
    assert len(route) == 170  # DRoA's route file, not a resampled copy


def test_reward_check_says_droa_s_verdict_and_strict_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from racer_tui.cli.main import main

    path = tmp_path / "reward.py"
    path.write_text("def reward_function(params):\n    return 1\n")
    assert main(["reward", "check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "DeepRacer on AWS would refuse it" in out
    assert "Method returned non-floating type value: 1" in out
    assert main(["reward", "check", str(path), "--strict"]) == 2
    err = capsys.readouterr().err
    assert (
        'DeepRacer on AWS would refuse it, saying "Method returned non-floating type value: 1"; '
        "fix that, or check without --strict." in err
    )
    path.write_text(ACCEPTED)
    assert main(["reward", "check", str(path), "--strict"]) == 0
    assert "DeepRacer on AWS would accept it" in capsys.readouterr().out

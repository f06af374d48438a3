"""Does a reward function pay for speed? A lap of the centre line at each speed, compared."""

from __future__ import annotations

import json

import pytest

from racer_tui.cli import main
from sim.reward_function import load_reward_source, load_template
from sim.reward_lap import lap_rewards, verdict
from sim.track_catalog import resolve_track

HAIRPIN = resolve_track("hairpin-circuit")
SPEEDS = (1.0, 2.0, 4.0)


def test_a_per_step_reward_for_the_centre_line_pays_a_slow_lap_more() -> None:
    # The classic mistake: follow_center_line pays 1 a step, and a slow lap has more steps.
    pays = lap_rewards(load_template("follow_center_line"), HAIRPIN, SPEEDS)
    assert [pay.speed for pay in pays] == list(SPEEDS)
    assert pays[0].steps == pytest.approx(2 * pays[1].steps, abs=1)
    assert pays[0].total > 3 * pays[-1].total
    assert "pays more for a slower lap" in verdict(pays)


def test_paying_for_speed_or_for_progress_made_is_seen_for_what_it_is() -> None:
    # Speed per step earns the same per lap at any speed (a faster lap has fewer steps);
    # its square is what pays a faster lap more.
    speed = load_reward_source("def reward_function(params):\n    return params['speed']\n", "s")
    assert "about the same for a lap at any speed" in verdict(lap_rewards(speed, HAIRPIN, SPEEDS))
    squared = load_reward_source(
        "def reward_function(params):\n    return params['speed'] ** 2\n", "s2"
    )
    assert "pays more for a faster lap" in verdict(lap_rewards(squared, HAIRPIN, SPEEDS))
    made = load_reward_source(
        "last = [0.0]\n"
        "def reward_function(params):\n"
        "    gain = params['progress'] - last[0]\n"
        "    last[0] = params['progress']\n"
        "    return max(gain, 0.0)\n",
        "progress.py",
    )
    # Each lap starts with the module loaded afresh, as a new car would.
    assert "about the same for a lap at any speed" in verdict(lap_rewards(made, HAIRPIN, SPEEDS))


def test_the_command_prints_the_laps_and_refuses_bad_speeds(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["reward", "lap", "follow_center_line", "--track", "hairpin-circuit"]
    assert main([*args, "--speeds", "1,4", "--json"]) == 0
    laps = json.loads(capsys.readouterr().out)["laps"]
    assert [lap["speed"] for lap in laps] == [1.0, 4.0] and laps[0]["total"] > laps[1]["total"]
    assert main(args) == 0
    assert "learns to drive slowly" in capsys.readouterr().out
    assert main([*args, "--speeds", "fast"]) == 2
    assert "--speeds must be m/s separated by commas" in capsys.readouterr().err


def test_a_function_that_only_costs_is_judged_by_its_totals_sign_and_all() -> None:
    from sim.reward_lap import LapPay

    costlier_fast = [LapPay(1.0, 100, -10.0), LapPay(4.0, 25, -10.5)]
    assert "pays more for a slower lap" in verdict(costlier_fast)
    cheaper_fast = [LapPay(1.0, 100, -10.0), LapPay(4.0, 25, -2.0)]
    assert "pays more for a faster lap" in verdict(cheaper_fast)

"""Does a reward function pay for speed, and for which line? A lap of the centre line and of
the line the reference driver drives at each speed, compared."""

from __future__ import annotations

import json

import pytest

from racer_tui.cli.main import main
from sim.coach.reward_line import load_template
from sim.deepracer.action_space import parse_action_space
from sim.reward.function import load_reward_source
from sim.reward.lap import CENTRE_LINE, LINES, REFERENCE_LINE, lap_rewards, line_verdict, verdict
from sim.tracks.catalog import resolve_track

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
    assert [(lap["line"], lap["speed"]) for lap in laps] == [
        (line, speed) for line in LINES for speed in (1.0, 4.0)
    ]
    assert laps[0]["total"] > laps[1]["total"]
    assert main(args) == 0
    assert "learns to drive slowly" in capsys.readouterr().out
    assert main([*args, "--speeds", "fast"]) == 2
    assert "--speeds must be m/s separated by commas" in capsys.readouterr().err


def test_a_function_that_only_costs_is_judged_by_its_totals_sign_and_all() -> None:
    from sim.reward.lap import LapPay

    costlier_fast = [LapPay(1.0, 100, -10.0), LapPay(4.0, 25, -10.5)]
    assert "pays more for a slower lap" in verdict(costlier_fast)
    cheaper_fast = [LapPay(1.0, 100, -10.0), LapPay(4.0, 25, -2.0)]
    assert "pays more for a faster lap" in verdict(cheaper_fast)


def test_each_step_of_a_lap_is_kept_in_order_with_the_steps_driven() -> None:
    steps = load_reward_source("def reward_function(params):\n    return params['steps']\n", "n")
    for pay in lap_rewards(steps, HAIRPIN, (2.0,), LINES):
        assert len(pay.rewards) == pay.steps - 1  # no call on the prepare step
        assert pay.rewards == tuple(float(n) for n in range(2, pay.steps + 1))
        assert pay.total == pytest.approx(sum(pay.rewards))


def test_the_reference_drivers_line_is_shorter_and_a_centre_line_function_pays_it_less() -> None:
    pays = lap_rewards(load_template("follow_center_line"), HAIRPIN, (1.0, 4.0), LINES)
    centre = [pay for pay in pays if pay.line == CENTRE_LINE]
    driven = [pay for pay in pays if pay.line == REFERENCE_LINE]
    assert [pay.speed for pay in driven] == [1.0, 4.0]
    assert driven[0].steps < centre[0].steps  # the reference driver cuts the corners
    assert set(centre[0].rewards) == {1.0}  # on the centre line, always the top band
    assert min(driven[0].rewards) < 1.0  # off the top band where it leaves the centre
    said = line_verdict(pays)
    assert said is not None and "pays less for the reference driver's line" in said
    wide = load_reward_source(
        "def reward_function(params):\n    return params['distance_from_center']\n", "wide"
    )
    said = line_verdict(lap_rewards(wide, HAIRPIN, (4.0,), LINES))
    assert said is not None and "pays more for the reference driver's line" in said
    assert line_verdict(centre) is None  # one line only: nothing to compare


def test_an_action_space_drives_its_own_speeds() -> None:
    discrete = parse_action_space(
        [
            {"steering_angle": -20, "speed": 2.5},
            {"steering_angle": 0, "speed": 1.0},
            {"steering_angle": 20, "speed": 2.5},
        ]
    )
    assert discrete.speeds() == (1.0, 2.5)
    continuous = parse_action_space(
        {"steering_angle": {"low": -30, "high": 30}, "speed": {"low": 0.5, "high": 2.0}}
    )
    assert continuous.speeds() == (0.5, 1.0, 1.5, 2.0)


def test_the_command_charts_both_lines_at_a_models_own_speeds(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    model = ["model", "new", "slowpoke", "--track", "hairpin-circuit", "--max-speed", "3"]
    assert main([*model, "--speed-levels", "2"]) == 0
    capsys.readouterr()
    assert main(["reward", "lap", "--model", "slowpoke", "--json"]) == 0
    laps = json.loads(capsys.readouterr().out)["laps"]
    assert [(lap["line"], lap["speed"]) for lap in laps] == [
        (line, speed) for line in LINES for speed in (1.5, 3.0)
    ]
    assert all(len(lap["rewards"]) == lap["steps"] - 1 for lap in laps)
    assert main(["reward", "lap", "--model", "slowpoke"]) == 0
    assert "One lap of hairpin-circuit: slowpoke's reward function" in capsys.readouterr().out
    monkeypatch.setenv("COLUMNS", "80")
    assert main(["reward", "lap", "follow_center_line", "--track", "hairpin-circuit"]) == 0
    out = capsys.readouterr().out
    chart = [row for row in out.splitlines() if " m/s " in row and "against" not in row]
    assert len(chart) == 8 and all(len(row) <= 80 for row in out.splitlines())
    assert chart[0].split()[:4] == ["centre", "line", "1", "m/s"] and len(chart[0]) == 80
    assert set(chart[0].split()[4]) == {"█"}  # 1 a step all the way round
    assert chart[4].split()[:4] == ["reference", "line", "1", "m/s"]
    assert chart[1].split()[:2] == ["2", "m/s"]
    assert len({row.index(" m/s ") for row in chart}) == 1  # the speeds line up
    assert "learns to drive slowly" in out and "holds a car to the centre" in out
    assert main(["reward", "lap"]) == 2
    assert "Give a reward function file or a template's name" in capsys.readouterr().err
    assert main(["reward", "lap", "--model", "nobody"]) == 2
    assert "there is no model named 'nobody'" in capsys.readouterr().err


def test_a_track_the_reference_driver_cannot_finish_is_charted_on_its_centre_line(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import racer_tui.cli.reward_commands
    import sim.reward.lap
    from sim.physics.reference_driver import ReferenceLap

    def off_the_road(track: object, *args: object, **kwargs: object) -> ReferenceLap:
        return ReferenceLap("hairpin-circuit", float("nan"), "off_track", 10.0)

    monkeypatch.setattr(sim.reward.lap, "reference_lap", off_the_road)
    pays = lap_rewards(load_template("follow_center_line"), HAIRPIN, (1.0, 2.0), LINES)
    assert [pay.line for pay in pays] == [CENTRE_LINE, CENTRE_LINE]
    assert line_verdict(pays) is None
    # The command (whose child process this test cannot reach) says why a line is missing.
    monkeypatch.setattr(racer_tui.cli.reward_commands, "lap_pay_of_source", lambda *a, **k: pays)
    assert main(["reward", "lap", "follow_center_line", "--track", "hairpin-circuit"]) == 0
    out = " ".join(capsys.readouterr().out.split())  # as read, whatever the terminal's width
    assert "does not finish a lap of hairpin-circuit, so only the centre line is charted" in out
    assert "reference line" not in out

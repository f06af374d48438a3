"""A racer's reward code runs in a child process with time limits: whatever it does, the
check answers in one sentence and the caller's process never runs a line of it."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from sim.reward_function import RewardFunctionError, check_reward_code, template_source
from sim.reward_probe import check_reward_source

LIMIT = 0.5  # seconds per call in these tests


def failure(source: str, **options: float) -> str:
    with pytest.raises(RewardFunctionError) as caught:
        check_reward_source(source, "reward.py", seconds=LIMIT, **options)
    return str(caught.value)


def test_a_template_is_checked_on_the_sample_and_a_lap() -> None:
    report = check_reward_source(
        template_source("follow_center_line"), "follow_center_line.py", track="hairpin-circuit"
    )
    assert report.sample_reward == 1.0
    assert report.track == "hairpin-circuit" and len(report.lap_rewards) > 100


def test_a_call_that_never_returns_is_stopped_at_its_line() -> None:
    source = "def reward_function(params):\n    while True:\n        pass\n"
    started = time.monotonic()
    message = failure(source)
    assert time.monotonic() - started < 20
    # Where it was stopped: the loop's line.
    assert message.startswith("reward.py line 2: reward_function did not return within 0.5 s")


def test_a_call_that_sleeps_is_stopped_too() -> None:
    source = "import time\ndef reward_function(params):\n    time.sleep(600)\n    return 1.0\n"
    assert "line 3: reward_function did not return within 0.5 s" in failure(source)


def test_a_file_that_hangs_while_loading_is_stopped() -> None:
    source = "while True:\n    pass\ndef reward_function(params):\n    return 1.0\n"
    assert "line 1: loading the file did not finish within 0.5 s" in failure(source)


def test_code_that_cannot_be_interrupted_meets_the_checks_deadline() -> None:
    # Signals blocked: only the parent's deadline can end it.
    source = (
        "import signal\n"
        "signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})\n"
        "def reward_function(params):\n"
        "    while True:\n"
        "        pass\n"
    )
    message = failure(source, deadline=5.0)
    assert "the check did not finish within 5 s, so it was stopped" in message


def test_a_function_that_ends_its_process_is_a_failure_not_a_pass() -> None:
    source = "import os\ndef reward_function(params):\n    os._exit(0)\n"
    assert "ended its own process (exit code 0) instead of returning a reward" in failure(source)


def test_keyboard_interrupt_and_huge_numbers_are_the_functions_errors() -> None:
    interrupt = "def reward_function(params):\n    raise KeyboardInterrupt\n"
    assert "line 2: reward_function raised KeyboardInterrupt" in failure(interrupt)
    huge = "def reward_function(params):\n    return 10**400\n"
    assert "too large to be a reward" in failure(huge)


def test_what_the_function_prints_is_not_taken_for_the_answer() -> None:
    source = "def reward_function(params):\n    print('{\"ok\": 1}')\n    return 0.5\n"
    assert check_reward_source(source, "reward.py").sample_reward == 0.5


def test_the_static_check_reads_the_code_without_running_it(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    check_reward_code(
        f"open({str(marker)!r}, 'w').write('x')\ndef reward_function(params):\n    return 1.0\n",
        "reward.py",
    )
    assert not marker.exists()
    with pytest.raises(RewardFunctionError, match=r"reward\.py line 2: syntax error"):
        check_reward_code("def reward_function(params):\n    return 1 +\n", "reward.py")
    with pytest.raises(RewardFunctionError, match="no reward_function found"):
        check_reward_code("def reward(params):\n    return 1.0\n", "reward.py")
    with pytest.raises(RewardFunctionError, match="line 1: reward_function must take exactly"):
        check_reward_code("def reward_function(params, extra):\n    return 1.0\n", "reward.py")
    check_reward_code("def reward_function(params, scale=2):\n    return 1.0\n", "reward.py")
    check_reward_code("reward_function = lambda params: 1.0\n", "reward.py")

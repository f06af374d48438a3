"""A racer's reward code runs in a child process with time limits: whatever it does, the
check answers in one sentence and the caller's process never runs a line of it."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest

from sim.coach.reward_line import template_source
from sim.reward.errors import RewardFunctionError
from sim.reward.function import check_reward_code
from sim.reward.probe import check_reward_source

LIMIT = 0.5  # seconds per call in these tests


def failure(source: str, **options: Any) -> str:
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


def test_code_that_blocks_the_interruption_is_ended_by_the_watchdog() -> None:
    source = (
        "import signal\n"
        "signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})\n"
        "def reward_function(params):\n"
        "    while True:\n"
        "        pass\n"
    )
    message = failure(source)
    # The watchdog reads where the main thread is stuck: the loop's line.
    assert message.startswith("reward.py line 4: reward_function did not return within 0.5 s")
    assert "could not be interrupted" in message


def test_code_that_holds_the_interpreter_meets_the_checks_deadline() -> None:
    # A catastrophic regular expression runs in C holding the interpreter: neither the
    # signal nor the watchdog thread gets a turn, so only the parent's deadline ends it.
    source = (
        "import re\n"
        "def reward_function(params):\n"
        "    re.match(r'(a+)+$', 'a' * 60 + 'b')\n"
        "    return 1.0\n"
    )
    message = failure(source, deadline=5.0)
    assert "the check did not finish within 5 s, so it was stopped" in message


def test_a_function_that_ends_its_process_is_named_with_its_line() -> None:
    source = "import os\ndef reward_function(params):\n    os._exit(0)\n"
    assert failure(source).startswith(
        "reward.py line 3: reward_function ends its process (os._exit)"
    )
    leaves = "import sys\ndef reward_function(params):\n    sys.exit(3)\n"
    assert failure(leaves).startswith("reward.py line 3: reward_function calls sys.exit()")


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


def test_a_function_that_swallows_its_interruption_is_still_stopped() -> None:
    # A bare `except:` catches the interruption; the call is failed when it returns...
    once = (
        "import time\n"
        "def reward_function(params):\n"
        "    try:\n"
        "        time.sleep(30)\n"
        "    except BaseException:\n"
        "        pass\n"
        "    return 1.0\n"
    )
    assert "reward_function did not return within 0.5 s" in failure(once)
    # ...and one that never returns is ended after four limits, in one sentence.
    forever = (
        "import time\n"
        "def reward_function(params):\n"
        "    while True:\n"
        "        try:\n"
        "            time.sleep(0.05)\n"
        "        except BaseException:\n"
        "            pass\n"
    )
    assert "could not be interrupted (it blocks or catches the interruption" in failure(forever)


def test_any_exception_the_function_raises_is_its_error() -> None:
    source = "def reward_function(params):\n    raise GeneratorExit('odd')\n"
    assert "line 2: reward_function raised GeneratorExit: odd" in failure(source)


def test_a_forged_answer_does_not_win_and_a_signal_is_refused() -> None:
    # The function can write to the answer's descriptor, but racer-tui's own answer is the
    # last line, and the process cannot be ended or signalled from the function.
    forged = (
        "import os\n"
        "def reward_function(params):\n"
        '    os.write(3, b\'{"ok": {"sample_reward": 5}}\\n\')\n'
        "    return 1.0\n"
    )
    assert check_reward_source(forged, "reward.py").sample_reward == 1.0
    killed = "import os\ndef reward_function(params):\n    os.kill(os.getpid(), 9)\n"
    assert failure(killed).startswith("reward.py line 3: reward_function sends a signal (os.kill)")

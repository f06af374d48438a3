"""`reward check` and `train` as a racer meets the reward's containment: one sentence and
exit code 2, for a function that starts a process and for a memory setting out of range."""

from __future__ import annotations

import json
from pathlib import Path

import psutil
import pytest

from racer_tui.cli.main import main
from sim.garage.options import new_model
from sim.reward import landlock

pytestmark = pytest.mark.usefixtures("no_leftover_processes")


def descendants() -> set[int]:
    """This process's descendants now (a test session may hold some of its own, such as
    multiprocessing's resource tracker: compare before and after)."""
    return {child.pid for child in psutil.Process().children(recursive=True)}


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str]:
    code = main(list(args))
    return code, capsys.readouterr().err


def test_reward_check_fails_a_function_that_starts_a_process(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    reward = tmp_path / "reward.py"
    reward.write_text(
        "import subprocess\n"
        "def reward_function(params):\n"
        "    subprocess.Popen(['sleep', '1000'])\n"
        "    return 1.0\n"
    )
    before = descendants()
    code, err = run_cli(capsys, "reward", "check", str(reward), "--track", "hairpin-circuit")
    assert code == 2
    assert err.strip() == (
        f"racer-tui: {reward} line 3: reward_function starts a process (subprocess.Popen), "
        "which a reward function may not do; remove it."
    )
    assert descendants() <= before


def test_reward_check_holds_the_function_to_the_memory_asked_for(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    reward = tmp_path / "reward.py"
    # 100 MB, taken on the first call and kept (a check calls the function hundreds of
    # times: filling 100 MB anew at each call cost seconds, and proved no more).
    reward.write_text(
        "kept = []\n\n\ndef reward_function(params):\n"
        "    if not kept:\n        kept.append(bytearray(10**8))\n    return 1.0\n"
    )
    code, err = run_cli(capsys, "reward", "check", str(reward), "--reward-memory-mb", "32")
    assert code == 2
    assert f"{reward} line 6: reward_function used more than 32 MB of memory" in err
    code, _ = run_cli(capsys, "reward", "check", str(reward), "--reward-memory-mb", "200")
    assert code == 0


@pytest.mark.parametrize("command", ["check", "train"])
def test_a_memory_setting_out_of_range_is_one_sentence(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, command: str
) -> None:
    if command == "check":
        reward = tmp_path / "reward.py"
        reward.write_text("def reward_function(params):\n    return 1.0\n")
        args = ["reward", "check", str(reward)]
    else:
        new_model("tiny")
        args = ["train", "tiny", "--minutes", "0.01"]
    code, err = run_cli(capsys, *args, "--reward-memory-mb", "1.5")
    assert code == 2
    assert err.strip() == (
        "racer-tui: --reward-memory-mb: the reward memory limit must be a whole number of MB "
        "from 16 to 1048576, not 1.5."
    )


def test_reward_check_says_whether_the_files_were_closed_off(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    reward = tmp_path / "reward.py"
    reward.write_text("def reward_function(params):\n    return 1.0\n")
    assert main(["reward", "check", str(reward), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["files_closed_off"] is (landlock.abi_version() >= 1)

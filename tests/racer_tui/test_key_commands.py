"""`racer-tui racer me | keys | admit` from the command line, on one machine."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from racer_tui.cli.main import main


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_the_racer_name_and_keys_of_this_machine(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = str(tmp_path / "league.db")
    assert run(capsys, "racer", "me", "--db", db)[1] == "No racer name is saved here.\n"
    code, out, _ = run(capsys, "racer", "me", "ana", "--db", db)
    assert code == 0 and "the next sync proposes its key under that name" in out
    assert run(capsys, "racer", "me", "--db", db)[1] == "This machine races as ana.\n"

    code, out, _ = run(capsys, "racer", "keys", "--db", db, "--json")
    (mine,) = json.loads(out)
    assert mine["this_machine"] and mine["status"] == "unknown"
    assert len(mine["fingerprint"].replace(" ", "")) == 16

    code, _, err = run(capsys, "racer", "admit", "bob", "--db", db)
    assert code == 2 and "only the league's organiser can admit keys" in err

    url = f"dir:{tmp_path / 'share'}"
    assert run(capsys, "sync", "init", url, "--db", db)[0] == 0
    code, out, _ = run(capsys, "racer", "me", "Ana Banana", "--db", db)
    assert "already known to the league (founder)" in out

"""Long bad input is echoed cut short: a sentence quotes at most 40 characters of a name
(120 of a path) with an ellipsis and says how long it was, never 10,000 characters; a name
no file can have (too long for the file system) is a name not found, not a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from racer_tui.cli.main import main
from sim.foundation.remedies import ECHO_CHARS, PATH_ECHO_CHARS, echoed, echoed_path

LONG = "a" * 10_000


def test_a_short_value_is_quoted_whole_and_a_long_one_cut() -> None:
    assert echoed("ana") == "'ana'"
    assert echoed("x" * ECHO_CHARS) == repr("x" * ECHO_CHARS)
    assert echoed(LONG) == f"'{'a' * ECHO_CHARS}…' (10,000 characters)"
    assert echoed_path("/home/ana/track.npy") == "/home/ana/track.npy"
    assert len(echoed_path("/" + LONG)) < PATH_ECHO_CHARS + 30


@pytest.mark.parametrize(
    ("command", "says"),
    [
        (["racer", "add", LONG], "cannot be a racer name"),
        (["racer", "me", LONG], "cannot be a racer name"),
        (["model", "new", LONG], "cannot be a model name"),
        (["model", "show", LONG], "there is no model named"),
        (["tracks", "show", LONG], "there is no track named"),
        (["model", "import", f"/tmp/{LONG}"], "does not exist"),
        (["tracks", "import", f"/tmp/{LONG}.npy", "--name", "okay"], "no such file"),
    ],
)
def test_commands_echo_a_10000_character_argument_cut_short(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, command: list[str], says: str
) -> None:
    code = main(["--db", str(tmp_path / "league.db"), *command])

    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and says in err
    assert len(err) < 400
    assert "(10,00" in err  # the length it was, said instead of shown

"""`racer-tui night bracket` and `night match`: a bracket night from the command line, from
its qualifying heats to the champion and the night's places."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.racer_tui.test_cli import run_cli


def test_a_bracket_night_from_qualifying_to_its_champion(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = ("--db", str(tmp_path / "league.db"))
    assert run_cli(capsys, "night", "new", "--name", "Cup", "--track", "beginner-oval", *db)[0] == 0
    for racer in ("ana", "bob", "cy"):
        assert (
            run_cli(capsys, "night", "add", "Cup", "--racer", racer, "--model", "reference", *db)[0]
            == 0
        )
    code, _, err = run_cli(capsys, "night", "bracket", "Cup", *db)
    assert code == 2 and "still qualifying (3 entrants have not raced their heat)" in err
    run_cli(capsys, "night", "draw", "Cup", "--seed", "1", *db)
    assert run_cli(capsys, "night", "run", "Cup", *db)[0] == 0

    code, out, err = run_cli(capsys, "night", "bracket", "Cup", "--laps", "1", *db)
    assert code == 0, err
    assert "single-elimination bracket of 3" in out and "each match 1 lap" in out
    assert "bye" in out  # three seeds in a bracket of four: the first seed goes through
    code, _, err = run_cli(capsys, "night", "bracket", "Cup", "--laps", "0", *db)
    assert code == 2 and "--laps: a match is 1 to 99 laps, not 0." in err

    code, out, err = run_cli(capsys, "night", "match", "Cup", "--matches", "1", *db)
    assert code == 0, err
    assert out.count(" beat ") == 1 and "Champion" not in out
    code, out, err = run_cli(capsys, "night", "match", "Cup", *db)
    assert code == 0, err
    assert out.count(" beat ") == 1 and "Champion: " in out
    champion = out.split("Champion: ")[1].split(".")[0]
    code, out, _ = run_cli(capsys, "night", "match", "Cup", *db)
    assert "no match is left to race" in out

    code, out, err = run_cli(capsys, "night", "close", "Cup", "--json", *db)
    assert code == 0, err
    places = json.loads(out)
    assert places[0]["racer"] == champion and places[0]["position"] == 1
    assert [p["position"] for p in places] == [1, 2, 3]
    code, out, _ = run_cli(capsys, "night", "show", "Cup", "--json", *db)
    bracket = json.loads(out)["bracket"]
    assert bracket["format"] == "single" and bracket["final_order"][0] == champion
    assert [m["id"] for m in bracket["matches"]] == ["W1-1", "W1-2", "W2-1"]
    assert "bye" in (bracket["matches"][0]["a"], bracket["matches"][0]["b"])
    assert bracket["matches"][-1]["winner"] == champion and bracket["matches"][-1]["race_id"]
    code, _, err = run_cli(
        capsys, "night", "add", "Cup", "--racer", "dee", "--model", "reference", *db
    )
    assert code == 2 and "closed" in err


def test_a_physical_bracket_is_drawn_here_and_timed_in_the_app(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from league.opening import open_league
    from tests.league.test_physical_brackets import physical_night

    with open_league(tmp_path / "league.db") as league:
        physical_night(league)
    db = ("--db", str(tmp_path / "league.db"))
    code, out, err = run_cli(capsys, "night", "bracket", "Garage", "--physical", *db)
    assert code == 0, err
    assert "bracket of 4 physical cars" in out and "the first to finish, penalties added" in out
    assert "Simulated cars are left out of the bracket (eve, fay are)" in out
    code, _, err = run_cli(capsys, "night", "match", "Garage", *db)
    assert code == 2
    assert "match W1-1 is between physical cars (ana v dan)" in err
    assert "time it on the real track in the app's Nights screen (r)" in err

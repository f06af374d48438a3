"""`racer-tui leaderboard --race-type head-to-head`: wins and losses in the recorded
head-to-head races, each racer's replayed starts, filters, and one sentence for what the
board cannot take."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from league.head_to_heads import record_head_to_head
from league.opening import open_league
from tests.league.sync.leagues import head_to_head
from tests.racer_tui.test_head_to_head_cli import run_cli


@pytest.fixture
def db(tmp_path: Path) -> str:
    path = tmp_path / "league.db"
    with open_league(path) as league:
        for seed, racers in enumerate((("ana", "bob"), ("bob", "ana"), ("ana", "cy")), start=1):
            record_head_to_head(league, head_to_head(*racers, seed=seed))
    return str(path)


def test_the_board_ranks_racers_by_wins_and_says_what_was_replayed(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    board = ("leaderboard", "--race-type", "head-to-head", "--db", db)
    code, out, err = run_cli(capsys, *board, "--format", "json")
    assert code == 0, err
    document = json.loads(out)
    assert document["board"] == "head-to-head" and document["races"] == 3
    rows = {row["racer"]: row for row in document["rows"]}
    assert sum(row["wins"] for row in rows.values()) == 3
    assert sum(row["starts"] for row in rows.values()) == 6
    assert rows["ana"]["starts"] == 3 and rows["ana"]["wins"] + rows["ana"]["losses"] == 3
    assert [row["rank"] for row in document["rows"]] == [1, 2, 3]
    wins = [row["wins"] for row in document["rows"]]
    assert wins == sorted(wins, reverse=True)
    assert all(row["replayed_starts"] == 0 for row in rows.values())  # none re-run yet

    assert run_cli(capsys, "sync", "verify", "--db", db)[0] == 0
    code, out, err = run_cli(capsys, *board)
    assert code == 0, err
    assert "Head-to-head: 3 races, ranked by wins" in out
    assert "3 of 3" in out and "2 of 2" in out  # every start replayed here
    code, out, err = run_cli(capsys, *board, "--verification", "replayed", "--racer", "cy")
    assert code == 0, err
    assert "cy" in out and "ana" not in out


def test_a_board_with_no_races_says_how_to_record_one(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, err = run_cli(
        capsys,
        "leaderboard",
        "--race-type",
        "head-to-head",
        "--track",
        "reinvent_base",
        "--db",
        str(tmp_path / "empty.db"),
    )
    assert code == 0, err
    assert out.startswith("No head-to-head races on reinvent_base yet: race models together")


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (("--by", "average"), "--by: a head-to-head board ranks by wins"),
        (("--sort", "racer"), "--sort: a head-to-head board is ranked by wins"),
        (("--format", "csv"), "--format csv: a head-to-head board is a table or JSON"),
    ],
)
def test_what_the_board_cannot_take_is_one_sentence(
    capsys: pytest.CaptureFixture[str], db: str, extra: tuple[str, ...], words: str
) -> None:
    code, out, err = run_cli(
        capsys, "leaderboard", "--race-type", "head-to-head", "--db", db, *extra
    )
    assert code == 2 and out == ""
    assert words in err and err.count("\n") == 1


def test_a_racer_named_keeps_their_rank_on_the_whole_board(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    board = ("leaderboard", "--race-type", "head-to-head", "--db", db, "--format", "json")
    code, out, err = run_cli(capsys, *board)
    assert code == 0, err
    whole = {row["racer"]: row for row in json.loads(out)["rows"]}
    for racer, row in whole.items():
        code, out, err = run_cli(capsys, *board, "--racer", racer)
        assert code == 0, err
        assert json.loads(out)["rows"] == [row]  # its rank, cars and counts
    assert [row["cars"] for row in whole.values()] == [["reference"]] * 3

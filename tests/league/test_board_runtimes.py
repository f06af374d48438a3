"""A board whose races were driven under several policy runtimes says so: their policies
computed with different numerics (sim.training.runtimes), which can decide a near tie
between two actions differently. Every front end shows it: the command line under the
table, JSON per row, the web page under the board, the app above the board and in a row's
detail."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from league.entries import EntryBreakdown
from league.leaderboard import Filters, leaderboard, mark_verification, mixed_runtimes
from league.opening import open_league
from league.races import record_race
from league.store import League
from racer_tui.app.screens.league import runtimes_line
from racer_tui.app.widgets.entry_detail import render_entry
from racer_tui.cli.main import main
from racer_tui.web.pages import league_leaderboard
from sim.foundation.ids import new_id
from sim.race.driver import reference_driver
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track

RULES = RaceRules(window_seconds=30.0)
OLD = "torch 2.13.0 x86_64 16caca443e89"
NEW = "v2 numpy 2.4.6 x86_64 d88d75e4be68"


def _races(league: League, runtimes: dict[str, str]) -> None:
    """One race per racer on the hairpin circuit, each claiming the runtime given."""
    track = resolve_track("hairpin-circuit")
    driven = run_race(track, RULES, reference_driver(track), racer="x", seed=1)
    for racer, runtime in runtimes.items():
        record_race(league, replace(driven, result_id=new_id(), racer=racer, runtime=runtime))


@pytest.fixture
def mixed(tmp_path: Path) -> Path:
    db = tmp_path / "league.db"
    with open_league(db) as league:
        _races(league, {"ana": OLD, "bo": NEW, "cy": ""})
    return db


def test_a_board_of_two_runtimes_says_so_in_every_format(
    mixed: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with open_league(mixed) as league:
        rows = leaderboard(league, Filters(), None)
        mark_verification(league, rows)
        assert {row.racer: row.runtime for row in rows} == {"ana": OLD, "bo": NEW, "cy": ""}
        note = mixed_runtimes(rows)
        assert note == (
            f"These races were driven under 2 policy runtimes ({OLD}; {NEW}): their policies "
            "computed with different numerics."
        )
        (board,) = league_leaderboard(league, None, frozenset()).boards
        assert board.to_json()["runtimes_note"] == note
        assert "2 policy runtimes" in runtimes_line(rows).plain
        ana = next(row for row in rows if row.racer == "ana")
        detail = render_entry(ana, EntryBreakdown(kind="race", found=True))
        assert f"policy runtime {OLD}" in detail.plain
    assert main(["leaderboard", "--db", str(mixed)]) == 0
    assert note in capsys.readouterr().out
    assert main(["leaderboard", "--db", str(mixed), "--format", "json"]) == 0
    rows_json = json.loads(capsys.readouterr().out)
    assert {row["racer_name"]: row["runtime"] for row in rows_json} == {
        "ana": OLD,
        "bo": NEW,
        "cy": None,
    }


def test_a_board_of_one_runtime_says_nothing_of_runtimes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "league.db"
    with open_league(db) as league:
        _races(league, {"ana": NEW, "bo": NEW, "cy": ""})
        rows = leaderboard(league, Filters(), None)
        mark_verification(league, rows)
        assert mixed_runtimes(rows) is None
        assert runtimes_line(rows).plain == ""
        (board,) = league_leaderboard(league, None, frozenset()).boards
        assert board.to_json()["runtimes_note"] is None
    assert main(["leaderboard", "--db", str(db)]) == 0
    assert "policy runtimes" not in capsys.readouterr().out

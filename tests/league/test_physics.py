"""Laps timed by different physics never meet on one leaderboard: every race and submission
carries the simulator's physics, and each physics has a board of its own."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from league.assembler import assemble
from league.leaderboard import Filters, leaderboard
from league.races import record_race
from league.records import record_body, store_record
from league.store import League
from league.submissions import submit
from league.sync.errors import RecordInvalidError
from league.sync.record import make_record
from league.sync.validate import check_record
from sim.deepracer.files import (
    evaluation_metrics_path,
    read_evaluation_physics,
    write_evaluation_metrics,
)
from sim.foundation.ids import content_hash, new_id
from sim.physics.labels import BEFORE_VERSIONING, CURRENT, DEEPRACER, board_suffix
from sim.race.result import RaceResult
from tests.league.helpers import TRACK, model_folder, race_result, trials

# A racer-tui physics other than today's, whatever today's version is.
OTHER = "racer-tui/7" if CURRENT != "racer-tui/7" else "racer-tui/8"


def _board(league: League) -> list[tuple[str, int, str]]:
    return [(row.track_name, row.rank, row.racer) for row in leaderboard(league, Filters())]


def test_a_race_records_the_physics_it_ran_on(league: League) -> None:
    result = race_result("ana", [10.0, 9.5])

    race_id = record_race(league, result)

    assert result.physics == CURRENT
    assert record_body(league, "races", race_id)["physics"] == CURRENT
    assert RaceResult.from_json(result.to_json()).physics == CURRENT


def test_laps_of_other_physics_are_ranked_on_a_board_of_their_own(league: League) -> None:
    record_race(league, race_result("ana", [10.0]))
    record_race(league, race_result("bo", [11.0]))
    # Faster, but timed by an older car: it must not push ana off the top of today's board.
    record_race(league, dataclasses.replace(race_result("cy", [8.0]), physics=OTHER))

    board = _board(league)

    assert board == [
        (TRACK, 1, "ana"),
        (TRACK, 2, "bo"),
        (TRACK + board_suffix(OTHER), 1, "cy"),
    ]
    assert board_suffix(OTHER).startswith(" (physics ")


def test_deepracer_evaluations_are_ranked_apart_from_racer_tui_laps(
    league: League, deepracer_dir: Path
) -> None:
    record_race(league, race_result("ana", [20.0]))
    console = assemble(str(deepracer_dir / "console-logs"), "dee", track=TRACK)
    assert console.physics == DEEPRACER
    submit(league, console)

    board = _board(league)

    assert (TRACK, 1, "ana") in board
    assert (TRACK + " (DeepRacer)", 1, "dee") in board


def test_an_evaluation_says_which_physics_timed_it(tmp_path: Path, league: League) -> None:
    folder = model_folder(tmp_path)
    old_stamp = "20240601120000"  # written without a physics key, as before versioning
    write_evaluation_metrics(folder / evaluation_metrics_path(old_stamp), trials([9.5]))
    assert assemble(str(folder), "ana").physics == BEFORE_VERSIONING
    stamp = "20250101120000"

    write_evaluation_metrics(folder / evaluation_metrics_path(stamp), trials([9.0]), CURRENT)

    assert read_evaluation_physics(folder / evaluation_metrics_path(stamp)) == CURRENT
    assert assemble(str(folder), "ana").physics == CURRENT


def test_a_record_from_before_physics_was_recorded_still_syncs_unchanged(
    league: League,
) -> None:
    result = race_result("ana", [10.0])
    record_race(league, result)
    body = record_body(league, "races", result.result_id)
    old_body = {key: value for key, value in body.items() if key != "physics"}
    old_id = new_id()

    check_record(make_record("race", old_id, old_body))  # valid without the field
    assert store_record(league, "races", old_id, old_body)

    # Stored without physics: its body (and so its content hash) is what was sent.
    assert record_body(league, "races", old_id) == old_body
    stored = league.query_one("SELECT content_hash FROM races WHERE id = ?", (old_id,))
    assert stored is not None and stored[0] == content_hash(old_body)


@pytest.mark.parametrize("bad", ["racer-tui/0", "racer-tui/x", "gazebo", ""])
def test_a_record_naming_an_unknown_physics_is_refused(league: League, bad: str) -> None:
    result = race_result("ana", [10.0])
    record_race(league, result)
    body = {**record_body(league, "races", result.result_id), "physics": bad}

    with pytest.raises(RecordInvalidError, match="physics"):
        check_record(make_record("race", new_id(), body))


def test_the_command_line_prints_each_board_on_its_own(
    league: League, capsys: pytest.CaptureFixture[str]
) -> None:
    from racer_tui.cli.main import main

    record_race(league, race_result("ana", [10.0]))
    record_race(league, dataclasses.replace(race_result("cy", [8.0]), physics=OTHER))
    league.close()

    code = main(["leaderboard", "--db", str(league.path), "--track", TRACK])

    out = capsys.readouterr().out
    assert code == 0
    assert f"Leaderboard: {TRACK}, ranked" in out
    assert f"Leaderboard: {TRACK}{board_suffix(OTHER)}, ranked" in out
    assert out.index("ana") < out.index(board_suffix(OTHER)) < out.index("cy")

"""Storing submissions: all-or-nothing, and sending the same one twice adds nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from league import submissions
from league.assembler import assemble
from league.store import League
from league.submissions import submit
from tests.league.helpers import model_folder

SHARED_TABLES = ("racers", "tracks", "submissions", "submission_laps", "entries", "board")


def _counts(league: League) -> dict[str, int]:
    return {table: league.query(f"SELECT count(*) FROM {table}")[0][0] for table in SHARED_TABLES}


def test_a_submission_is_stored_with_its_laps_and_ranks(tmp_path: Path, league: League) -> None:
    stored = submit(league, assemble(str(model_folder(tmp_path)), "ana"))
    assert _counts(league) == {
        "racers": 1,
        "tracks": 1,
        "submissions": 1,
        "submission_laps": 3,
        "entries": 1,
        "board": 3,  # the racer's best entry under each ranking method
    }
    entry = league.query_one("SELECT * FROM entries WHERE entry_id = ?", (stored.submission_id,))
    assert entry["best_lap"] == 12.1
    assert entry["valid_laps"] == 3


def test_the_same_submission_twice_is_stored_once(tmp_path: Path, league: League) -> None:
    submission = assemble(str(model_folder(tmp_path)), "ana")
    first = submit(league, submission)
    again = submit(league, assemble(str(model_folder(tmp_path / "copy")), "ANA"))
    assert again.duplicate and again.submission_id == first.submission_id
    assert _counts(league)["submissions"] == 1
    other_racer = submit(league, assemble(str(model_folder(tmp_path / "b")), "bob"))
    assert not other_racer.duplicate


def test_an_interrupted_submit_leaves_no_partial_rows(
    tmp_path: Path, league: League, monkeypatch: pytest.MonkeyPatch
) -> None:
    before = _counts(league)

    def fail_after_the_submission_row(*args: object) -> None:
        raise KeyboardInterrupt  # Ctrl+C between the submission row and its laps

    monkeypatch.setattr(submissions, "insert_laps", fail_after_the_submission_row)
    with pytest.raises(KeyboardInterrupt):
        submit(league, assemble(str(model_folder(tmp_path)), "ana"))
    assert _counts(league) == before
    monkeypatch.undo()
    submit(league, assemble(str(model_folder(tmp_path / "retry")), "ana"))
    assert _counts(league)["submission_laps"] == 3

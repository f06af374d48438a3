"""This machine's racer name, where an entry lands on the board, and submitting a model
folder or a race the way the app does."""

from __future__ import annotations

from pathlib import Path

import pytest

from league.assembler import assemble
from league.board_place import board_place, ordinal, place_sentence
from league.errors import LeagueError
from league.local_racer import local_racer_name, save_local_racer_name
from league.races import race_result as stored_race
from league.races import record_race_as
from league.store import League
from league.submissions import submit_model
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, model_folder, race_result


def test_the_racer_name_is_nobody_in_an_empty_league_until_one_is_saved(
    league: League,
) -> None:
    assert local_racer_name(league) == ""  # never the machine's user name ("root")
    assert save_local_racer_name(league, "  Ada [b]L[/b]  ") == "Ada [b]L[/b]"
    assert local_racer_name(league) == "Ada [b]L[/b]"  # plain text, kept literally


def test_without_a_saved_name_the_leagues_last_racer_is_offered(league: League) -> None:
    record_race_as(league, race_result("x", [10.0], started_at="2024-05-01T19:00:00.000Z"), "Bo")
    record_race_as(league, race_result("y", [10.0], started_at="2024-05-02T19:00:00.000Z"), "Cy")
    record_race_as(league, race_result("z", [10.0], started_at="2024-04-01T19:00:00.000Z"), "Di")

    assert local_racer_name(league) == "Cy"
    save_local_racer_name(league, "Ada")
    assert local_racer_name(league) == "Ada"


def test_a_racer_name_with_a_line_break_is_refused(league: League) -> None:
    with pytest.raises(LeagueError, match="cannot be a racer name"):
        save_local_racer_name(league, "Ada\nLovelace")
    assert local_racer_name(league) == ""


@pytest.mark.parametrize(
    ("number", "text"),
    [(1, "1st"), (2, "2nd"), (3, "3rd"), (4, "4th"), (11, "11th"), (13, "13th"), (22, "22nd")],
)
def test_ordinals(number: int, text: str) -> None:
    assert ordinal(number) == text


def test_a_submitted_model_is_placed_on_its_tracks_board(league: League, tmp_path: Path) -> None:
    fast = model_folder(tmp_path, "fast", laps=(10.0, 10.5))
    slow = model_folder(tmp_path, "slow", laps=(12.0,))
    submit_model(league, str(fast), "Ada")
    submission, outcome = submit_model(league, str(slow), "Bo", model_name="slowpoke")
    assert submission.model_name == "slowpoke" and not outcome.duplicate
    place = board_place(league, "bo", submission.track_hash)  # names match any case
    assert place is not None
    assert (place.rank, place.entries, place.display_name) == (2, 2, "Bo")
    assert place_sentence(place, outcome.submission_id) == (
        f"Bo is 2nd of 2 on {TRACK}'s leaderboard."
    )
    _, again = submit_model(league, str(slow), "Bo", model_name="slowpoke")
    assert again.duplicate and again.submission_id == outcome.submission_id


def test_a_worse_entry_is_told_that_the_earlier_one_counts(league: League, tmp_path: Path) -> None:
    track = resolve_track(TRACK)
    best = race_result("app-label", [9.0], model="car")
    worse = race_result("app-label", [11.0], model="car")
    record_race_as(league, best, "Ada")
    record_race_as(league, worse, "Ada")
    place = board_place(league, "Ada", track.content_hash)
    assert place is not None and place.entry_id == best.result_id
    sentence = place_sentence(place, worse.result_id)
    assert sentence.endswith("with an earlier entry, which this one does not beat.")
    assert board_place(league, "nobody", track.content_hash) is None
    assert "not on that track's leaderboard" in place_sentence(None, worse.result_id)


def test_a_race_is_recorded_as_the_racer_and_never_changes_hands(league: League) -> None:
    result = race_result("my-model", [10.0, 10.2])
    race_id = record_race_as(league, result, "Ada")
    assert stored_race(league, race_id).racer == "Ada"
    assert record_race_as(league, result, "Ada") == race_id  # the same again: a no-op
    with pytest.raises(LeagueError, match="already recorded with different content"):
        record_race_as(league, result, "Bo")


def test_a_model_without_an_evaluation_says_to_evaluate_it(league: League, tmp_path: Path) -> None:
    folder = model_folder(tmp_path, "fresh")
    for evaluation in folder.glob("metrics/EvaluationMetrics-*.json"):
        evaluation.unlink()
    with pytest.raises(LeagueError, match="evaluate the model first"):
        submit_model(league, str(folder), "Ada")
    assert league.conn.execute("SELECT count(*) FROM submissions").fetchone()[0] == 0


def test_an_evaluation_older_than_the_last_training_needs_a_confirmation(
    league: League, tmp_path: Path
) -> None:
    folder = model_folder(tmp_path, "retrained", stamp="20240501120000")
    state = folder / "training-state.json"
    state.write_text(
        '{"state": "finished", "elapsed_seconds": 60, "updated_at": "2024-05-02T08:00:00+00:00"}'
    )

    with pytest.raises(LeagueError, match=r"made before it last trained.*--stale-ok"):
        submit_model(league, str(folder), "Ada")
    assert league.conn.execute("SELECT count(*) FROM submissions").fetchone()[0] == 0

    submission, outcome = submit_model(league, str(folder), "Ada", allow_stale=True)
    assert submission.stale is not None and not outcome.duplicate

    state.write_text(
        '{"state": "finished", "elapsed_seconds": 60, "updated_at": "2024-05-01T08:00:00+00:00"}'
    )
    assert assemble(str(folder), "Ada").stale is None  # trained, then evaluated: fresh

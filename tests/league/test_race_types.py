"""DeepRacer's race types never share a board: a lap among boxes or bot cars is ranked on
its track's board of that race type, apart from the track's time trials, and a league
made before race types existed opens with every board it had, now its time trials'."""

from __future__ import annotations

import sqlite3
from dataclasses import replace
from pathlib import Path

import pytest

from league.assembler import assemble
from league.board_place import board_place
from league.errors import LeagueError
from league.leaderboard import Filters, leaderboard, race_types_on
from league.migrations import MIGRATIONS
from league.opening import open_league
from league.race_types import (
    HEAD_TO_BOT,
    OBJECT_AVOIDANCE,
    TIME_TRIAL,
    board_name,
    parse_race_type,
)
from league.races import best_lap_race, record_race
from league.records import record_body
from league.store import League
from league.submissions import submit
from sim.foundation.ids import content_hash
from sim.physics.labels import CURRENT
from sim.race.rules import preset_rules
from tests.league.helpers import TRACK, model_folder, race_result

BOXES = preset_rules("object-avoidance")
BOTS = preset_rules("head-to-bot")


def _board(league: League, filters: Filters | None = None) -> list[tuple[str, int, str, str]]:
    return [
        (row.track_name, row.rank, row.racer, row.race_type)
        for row in leaderboard(league, filters or Filters())
    ]


def test_a_time_trial_and_an_object_avoidance_race_rank_on_separate_boards(
    league: League,
) -> None:
    record_race(league, race_result("ana", [10.0]))
    record_race(league, race_result("bo", [11.0]))
    # Quicker than both, but among boxes: it must not push ana off the time trials' top.
    record_race(league, race_result("cy", [9.0], rules=BOXES))
    record_race(league, race_result("ana", [12.0], rules=BOXES))

    assert _board(league) == [
        (TRACK, 1, "ana", TIME_TRIAL),
        (TRACK, 2, "bo", TIME_TRIAL),
        (f"{TRACK} (object avoidance)", 1, "cy", OBJECT_AVOIDANCE),
        (f"{TRACK} (object avoidance)", 2, "ana", OBJECT_AVOIDANCE),
    ]
    track_hash = leaderboard(league, Filters())[0].track_hash
    boxes = Filters(track_hash=track_hash, race_type=OBJECT_AVOIDANCE)
    assert [row.racer for row in leaderboard(league, boxes)] == ["cy", "ana"]
    trials = Filters(track_hash=track_hash, race_type=TIME_TRIAL)
    assert [row.racer for row in leaderboard(league, trials)] == ["ana", "bo"]
    assert race_types_on(league, track_hash) == [TIME_TRIAL, OBJECT_AVOIDANCE]


def test_every_track_of_one_race_type_is_read_in_order(league: League) -> None:
    from sim.tracks.catalog import resolve_track

    hairpin = resolve_track("hairpin-circuit")
    record_race(league, race_result("ana", [10.0], rules=BOXES))
    record_race(league, race_result("bo", [30.0], track=hairpin, rules=BOXES))
    record_race(league, race_result("cy", [25.0], track=hairpin, rules=BOXES))
    record_race(league, race_result("dee", [9.0]))
    record_race(league, race_result("eve", [9.5], rules=BOTS))

    assert _board(league, Filters(race_type=OBJECT_AVOIDANCE)) == [
        (f"{TRACK} (object avoidance)", 1, "ana", OBJECT_AVOIDANCE),
        ("hairpin-circuit (object avoidance)", 1, "cy", OBJECT_AVOIDANCE),
        ("hairpin-circuit (object avoidance)", 2, "bo", OBJECT_AVOIDANCE),
    ]
    assert _board(league, Filters(race_type=HEAD_TO_BOT)) == [
        (f"{TRACK} (head-to-bot)", 1, "eve", HEAD_TO_BOT)
    ]


def test_a_racer_is_placed_on_the_board_of_their_entrys_race_type(league: League) -> None:
    record_race(league, race_result("ana", [10.0]))
    record_race(league, race_result("bo", [11.0]))
    boxed = race_result("bo", [14.0], rules=BOXES)
    record_race(league, boxed)
    track_hash = boxed.track_hash

    on_trials = board_place(league, "bo", track_hash)
    on_boxes = board_place(league, "bo", track_hash, race_type=OBJECT_AVOIDANCE)

    assert on_trials is not None and (on_trials.rank, on_trials.entries) == (2, 2)
    assert on_boxes is not None and (on_boxes.rank, on_boxes.entries) == (1, 1)
    assert on_boxes.entry_id == boxed.result_id
    assert on_boxes.track_name == f"{TRACK} (object avoidance)"


def test_a_ghost_for_a_time_trial_is_never_a_lap_among_boxes(league: League) -> None:
    from sim.race.engine import run_race
    from sim.race.rules import RaceRules
    from sim.tracks.catalog import resolve_track

    trace = run_race(resolve_track(TRACK), RaceRules(window_seconds=10.0), keep_trace=True).trace
    trial = race_result("ana", [12.0]).with_trace(trace)
    boxed = race_result("bo", [9.0], rules=BOXES).with_trace(trace)  # quicker, among boxes
    record_race(league, trial)
    record_race(league, boxed)

    assert best_lap_race(league, trial.track_hash, CURRENT) == trial.result_id
    assert best_lap_race(league, trial.track_hash, CURRENT, OBJECT_AVOIDANCE) == boxed.result_id


def _set_up_for(folder: Path, race_type: str) -> Path:
    """The model folder, its training_params.yaml saying RACE_TYPE: `race_type`."""
    from sim.deepracer.files import TRAINING_PARAMS, TrainingParams, write_training_params
    from sim.tracks.catalog import resolve_track

    track = resolve_track(TRACK)
    params = TrainingParams(world_name=track.name, track_hash=track.content_hash)
    write_training_params(folder / TRAINING_PARAMS, replace(params, race_type=race_type))
    return folder


def test_a_submission_is_ranked_on_the_board_of_its_models_race_type(
    league: League, tmp_path: Path
) -> None:
    trial = submit(league, assemble(str(model_folder(tmp_path, "trial", laps=(12.0,))), "ana"))
    boxes = model_folder(tmp_path, "boxes", laps=(11.0,))  # quicker, among its boxes
    boxed = submit(league, assemble(str(_set_up_for(boxes, "OBJECT_AVOIDANCE")), "bex"))

    assert _board(league) == [
        (TRACK, 1, "ana", TIME_TRIAL),
        (f"{TRACK} (object avoidance)", 1, "bex", OBJECT_AVOIDANCE),
    ]
    # A time trial's record is as it always was; the other says its race type.
    assert "race_type" not in record_body(league, "submissions", trial.submission_id)
    body = record_body(league, "submissions", boxed.submission_id)
    assert body["race_type"] == OBJECT_AVOIDANCE
    for made in (trial, boxed):  # each hashed as its record's body says
        stored = league.query_one(
            "SELECT content_hash FROM submissions WHERE id = ?", (made.submission_id,)
        )
        body = record_body(league, "submissions", made.submission_id)
        assert stored is not None and stored[0] == content_hash(body)
    place = board_place(league, "bex", league_track_hash(league), race_type=OBJECT_AVOIDANCE)
    assert place is not None and place.rank == 1


def test_a_models_unknown_race_type_is_one_sentence_naming_the_file(tmp_path: Path) -> None:
    folder = _set_up_for(model_folder(tmp_path), "DRAG_RACE")
    with pytest.raises(LeagueError) as raised:
        assemble(str(folder), "ana")
    assert str(raised.value) == (
        f"{folder / 'training_params.yaml'}: RACE_TYPE must be one of TIME_TRIAL, "
        "OBJECT_AVOIDANCE, HEAD_TO_BOT, not 'DRAG_RACE'."
    )


def league_track_hash(league: League) -> str:
    return str(leaderboard(league, Filters())[0].track_hash)


def test_board_names_say_the_race_type_and_the_physics() -> None:
    assert board_name("oval", CURRENT, TIME_TRIAL) == "oval"
    assert board_name("oval", "deepracer", TIME_TRIAL) == "oval (DeepRacer)"
    assert board_name("oval", CURRENT, OBJECT_AVOIDANCE) == "oval (object avoidance)"
    assert board_name("oval", "racer-tui/1", HEAD_TO_BOT) == "oval (head-to-bot, physics 1)"


@pytest.mark.parametrize(
    ("typed", "race_type"),
    [
        ("time-trial", TIME_TRIAL),
        ("Object_Avoidance", OBJECT_AVOIDANCE),
        (" head-to-bot", HEAD_TO_BOT),
    ],
)
def test_race_types_are_read_as_typed(typed: str, race_type: str) -> None:
    assert parse_race_type(typed) == race_type


def test_an_unknown_race_type_is_one_sentence_listing_them() -> None:
    with pytest.raises(LeagueError) as raised:
        parse_race_type("drag race")
    assert str(raised.value) == (
        "--race-type must be one of time-trial, object-avoidance, head-to-bot, not 'drag race'."
    )


# --- a league from before race types ----------------------------------------------------------

_V9_CACHE_COLUMNS = {
    "entries": "entry_id, kind, racer, track_hash, physics, model_name, night_id, recorded_at, "
    "laps_driven, valid_laps, offtracks, best_lap, average_lap, native_method, score_best_lap, "
    "offtracks_best_lap, score_best_average, offtracks_best_average, score_total_time, "
    "offtracks_total_time",
    "board": "method, track_hash, physics, unscored, score, scoring_offtracks, valid_laps, "
    "recorded_at, racer, entry_id, kind, model_name, night_id, best_lap, average_lap, "
    "offtracks, laps_driven",
}
_SHARED = ("racers", "tracks", "submissions", "submission_laps", "races", "race_laps")


def _version_9_league(path: Path, made: Path) -> None:
    """A league as racer-tui left it before race types (schema version 9): the shared rows
    and the leaderboard cache of the league at `made`, in version 9's tables."""
    conn = sqlite3.connect(path)
    for migration in MIGRATIONS[:9]:
        migration.apply(conn)
    conn.execute("ATTACH DATABASE ? AS made", (str(made),))
    for table in _SHARED:  # version 9's columns (later ones are NULL in these rows)
        columns = ", ".join(row[1] for row in conn.execute(f"PRAGMA main.table_info({table})"))
        conn.execute(f"INSERT INTO main.{table} ({columns}) SELECT {columns} FROM made.{table}")
    for table, columns in _V9_CACHE_COLUMNS.items():
        conn.execute(f"INSERT INTO main.{table} ({columns}) SELECT {columns} FROM made.{table}")
    conn.execute("PRAGMA user_version = 9")
    conn.commit()
    conn.execute("DETACH DATABASE made")
    conn.close()


def test_a_league_from_before_race_types_opens_with_its_boards_intact(tmp_path: Path) -> None:
    made = tmp_path / "made.db"
    with open_league(made) as league:
        record_race(league, race_result("ana", [10.0, 9.8]))
        record_race(league, race_result("bo", [11.0], offtracks=[4]))  # too many: no lap counts
        record_race(league, race_result("cy", [10.5], started_at="2024-05-02T19:00:00.000Z"))
        submit(league, assemble(str(model_folder(tmp_path, laps=(9.9, 12.0))), "dee"))
    old = tmp_path / "old.db"
    _version_9_league(old, made)
    conn = sqlite3.connect(old)
    board_before = conn.execute(
        f"SELECT {_V9_CACHE_COLUMNS['board']} FROM board ORDER BY method, track_hash, racer"
    ).fetchall()
    conn.close()
    assert len(board_before) == 4 * 3  # four racers, three ranking methods

    with open_league(old) as upgraded:
        version = upgraded.query_one("PRAGMA user_version")
        assert version is not None and version[0] == len(MIGRATIONS)
        board_after = upgraded.conn.execute(
            f"SELECT {_V9_CACHE_COLUMNS['board']}, race_type FROM board "
            "ORDER BY method, track_hash, racer"
        ).fetchall()
        rows = leaderboard(upgraded, Filters())

    assert [row[:-1] for row in board_after] == board_before
    assert {row[-1] for row in board_after} == {TIME_TRIAL}
    assert [(row.rank, row.racer, row.track_name) for row in rows] == [
        (1, "ana", TRACK),
        (2, "dee", TRACK),
        (3, "cy", TRACK),
        (4, "bo", TRACK),
    ]


def test_the_recorded_races_list_says_a_race_type_that_is_not_a_time_trial(
    league: League,
) -> None:
    from league.races import recent_races

    record_race(league, race_result("ana", [10.0], started_at="2024-05-01T19:00:00.000Z"))
    record_race(league, race_result("bex", [12.0], rules=BOXES))

    labels = [(race.racer, race.track_label) for race in recent_races(league)]

    assert sorted(labels) == [("ana", TRACK), ("bex", f"{TRACK} (object avoidance)")]

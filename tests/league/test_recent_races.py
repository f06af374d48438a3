"""Recorded races for the app: the newest first, ready to replay, and a leaderboard entry's
parts (a submission's files, a race's laps) read by the league rather than by a widget."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from league.assembler import assemble
from league.corrections import disqualify_lap
from league.entries import entry_breakdown
from league.errors import LeagueError
from league.nights import new_night
from league.races import race_replay, recent_races, record_race
from league.store import League
from league.submissions import submit
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import model_folder, race_result

SHORT = RaceRules(window_seconds=20.0)


def test_recent_races_are_newest_first_with_what_the_list_shows(league: League) -> None:
    oval = resolve_track("beginner-oval")
    hairpin = resolve_track("hairpin-circuit")
    night = new_night(league, oval, name="friday")
    first = record_race(league, race_result("ada", [12.0, 11.5], model="ada-car"))
    second = record_race(league, race_result("bob", [20.0], track=hairpin), night_id=None)
    third = record_race(league, race_result("cy", [13.0, 12.5, 14.0]), night.id)

    races = recent_races(league)
    assert [race.race_id for race in races] == [third, second, first]
    newest = races[0]
    assert (newest.racer, newest.track_name, newest.night_name) == ("cy", "beginner-oval", "friday")
    assert newest.best_lap == 12.5 and newest.valid_laps == 3 and newest.laps_driven == 3
    assert races[1].track_name == "hairpin-circuit" and races[1].night_name is None
    assert not any(race.has_trace for race in races)  # the helper's results carry none

    assert [race.race_id for race in recent_races(league, limit=2)] == [third, second]
    on_oval = recent_races(league, track_hash=oval.content_hash)
    assert [race.racer for race in on_oval] == ["cy", "ada"]
    assert recent_races(league, track_hash="no-such-track") == []


def test_a_disqualified_lap_no_longer_counts_in_the_list(league: League) -> None:
    race_id = record_race(league, race_result("ada", [12.0, 11.5]))
    disqualify_lap(league, race_id, 2, reason="cut the chicane", by="host")
    (race,) = recent_races(league)
    assert race.best_lap == 12.0 and race.valid_laps == 1 and race.laps_driven == 2


def test_a_race_with_its_trace_replays_on_its_track(league: League) -> None:
    track = resolve_track("beginner-oval")
    result = run_race(track, SHORT, racer="ref", keep_trace=True)
    record_race(league, result)
    (listed,) = recent_races(league)
    assert listed.has_trace
    replay = race_replay(league, result.result_id)
    assert replay.track.content_hash == track.content_hash
    assert replay.result.trace is not None and len(replay.result.trace) > 10
    assert [lap.time_seconds for lap in replay.result.laps] == [
        lap.time_seconds for lap in result.laps
    ]


def test_a_race_that_cannot_be_replayed_says_why(league: League) -> None:
    untraced = record_race(league, race_result("ada", [12.0]))
    with pytest.raises(LeagueError, match="has no trace here"):
        race_replay(league, untraced)
    result = run_race(resolve_track("beginner-oval"), SHORT, racer="ref", keep_trace=True)
    elsewhere = replace(result, track_name="moon-base", track_hash="f" * 64)
    record_race(league, elsewhere)
    with pytest.raises(LeagueError, match="'moon-base', which is not on this machine"):
        race_replay(league, elsewhere.result_id)
    with pytest.raises(LeagueError, match="there is no race"):
        race_replay(league, "0" * 26)


def test_a_submission_breaks_down_into_its_files(league: League, tmp_path: Path) -> None:
    folder = model_folder(tmp_path, "dee-car", laps=(12.5, 12.1, 12.9))
    submitted = submit(league, assemble(str(folder), "dee"))
    parts = entry_breakdown(league, "submission", submitted.submission_id)
    assert parts.found and parts.submission is not None
    files = parts.submission
    assert files.action_space is not None and files.action_space["type"] == "discrete"
    assert files.sensors == ["vector"]
    assert files.hyperparameters is not None and files.hyperparameters["batch_size"] == 64
    assert files.training is not None and files.training["episodes"] == 20
    assert files.evaluation_file == "EvaluationMetrics-20240501120000.json"
    assert [trial.time_seconds for trial in files.trials] == [12.5, 12.1, 12.9]
    assert all(trial.completed for trial in files.trials)
    assert not entry_breakdown(league, "submission", "0" * 26).found


def test_a_race_breaks_down_into_its_laps(league: League) -> None:
    race_id = record_race(league, race_result("ada", [12.0, 11.5], offtracks=[0, 4]))
    parts = entry_breakdown(league, "race", race_id)
    assert parts.found and not parts.has_trace and parts.submission is None
    assert [(lap.number, lap.offtracks, lap.valid) for lap in parts.race_laps] == [
        (1, 0, True),
        (2, 4, False),
    ]
    assert parts.race_laps[1].penalty_seconds == 12.0
    assert not entry_breakdown(league, "race", "0" * 26).found

"""Race results in the league: laps, frozen rules, model hash and a local trace."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from league.errors import LeagueError
from league.races import race_result, race_trace, record_race
from league.store import League
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK
from tests.league.helpers import race_result as make_result


def test_a_recorded_race_reads_back_the_same(league: League) -> None:
    rules = RaceRules(window_seconds=60.0, max_offtracks_per_lap=None)
    result = make_result("ana", [12.0, 11.5, 13.0], offtracks=[0, 2], rules=rules)
    race_id = record_race(league, result)
    assert race_id == result.result_id
    back = race_result(league, race_id)
    assert back.to_json() == result.to_json()
    assert back.rules == rules
    assert league.query_one("SELECT model_hash FROM races")[0] == "hash-car"


def test_recording_twice_is_a_no_op_but_other_content_under_the_same_id_is_refused(
    league: League,
) -> None:
    result = make_result("ana", [12.0])
    record_race(league, result)
    record_race(league, result)
    assert league.query_one("SELECT count(*) FROM races")[0] == 1
    tampered = replace(result, model_hash="someone-else")
    with pytest.raises(LeagueError, match="already recorded with different content"):
        record_race(league, tampered)


def test_the_trace_is_kept_locally_and_reads_back(league: League) -> None:
    track = resolve_track(TRACK)
    result = run_race(track, RaceRules(window_seconds=12.0), racer="ana", seed=3)
    assert result.trace is not None
    record_race(league, result)
    trace = race_trace(league, result.result_id)
    assert trace is not None
    assert np.array_equal(trace.x, result.trace.x)
    assert trace.statuses() == result.trace.statuses()
    shared_columns = [row[1] for row in league.query("PRAGMA table_info(races)")]
    assert not any("trace" in column for column in shared_columns)


def test_a_race_without_a_trace_has_none(league: League) -> None:
    result = make_result("ana", [12.0])
    record_race(league, result)
    assert race_trace(league, result.result_id) is None

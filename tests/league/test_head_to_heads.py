"""Head-to-head races in the league: one record per race, every car's laps held to the
track's floor, never on a lap board; wins and losses from the recorded races."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from league.errors import LeagueError
from league.head_to_heads import (
    MAX_INCIDENTS,
    MAX_TEXT,
    CarPlace,
    RecordedHeadToHead,
    head_to_head_board,
    head_to_head_races,
    lap_from_list,
    lap_list,
    record_between,
    record_head_to_head,
)
from league.races import lap_rows
from league.store import League
from league.sync.record import MAX_STRING_CHARS
from sim.race.head_to_head import HeadToHeadResult, Incident
from sim.race.result import LapRecord
from sim.race.rules import DEFAULT_RULES
from tests.league.sync.leagues import head_to_head


@pytest.fixture(scope="module")
def race() -> HeadToHeadResult:
    return head_to_head("ana", "bob", seed=2)


def test_a_race_is_recorded_once_with_every_car_in_order(
    league: League, race: HeadToHeadResult
) -> None:
    assert record_head_to_head(league, race) == race.race_id
    assert record_head_to_head(league, race) == race.race_id  # the same race again: nothing
    assert league.query_one("SELECT count(*) FROM head_to_heads")[0] == 1
    [recorded] = head_to_head_races(league)
    assert recorded.id == race.race_id and recorded.seed == 2
    assert recorded.winner == race.winner.result.racer
    assert [place.racer for place in recorded.places] == [c.result.racer for c in race.cars]
    for place, car in zip(recorded.places, race.cars, strict=True):
        assert place.position == car.position
        assert place.laps_completed == car.laps_completed == len(car.result.laps)
        assert place.finished_at == car.finished_at and place.gap_seconds == car.gap_seconds
        valid = [lap.time_seconds for lap in car.result.laps if lap.valid]
        assert place.best_lap == min(valid, default=None)
    assert head_to_head_races(league, track_hash="0" * 64) == []
    # A car's laps rank on no lap board: they are not races of the leaderboard cache.
    assert league.query_one("SELECT count(*) FROM races")[0] == 0
    assert league.query_one("SELECT count(*) FROM entries")[0] == 0


def test_the_same_id_with_other_content_is_refused(league: League, race: HeadToHeadResult) -> None:
    record_head_to_head(league, race)
    changed = replace(race, seed=race.seed + 1)
    with pytest.raises(LeagueError, match="already recorded with different content"):
        record_head_to_head(league, changed)


def test_a_lap_no_car_could_drive_is_refused(league: League, race: HeadToHeadResult) -> None:
    first = race.cars[0]
    impossible = LapRecord(
        number=1,
        time_seconds=0.5,
        raw_seconds=0.5,
        penalty_seconds=0.0,
        offtracks=0,
        valid=True,
        started_at=0.0,
    )
    forged_car = replace(first, result=replace(first.result, laps=(impossible,)))
    forged = replace(race, cars=(forged_car, *race.cars[1:]))
    with pytest.raises(LeagueError, match="not recorded"):
        record_head_to_head(league, forged)
    assert league.query_one("SELECT count(*) FROM head_to_heads")[0] == 0


def test_only_a_head_to_head_race_and_a_known_night(league: League, race: HeadToHeadResult) -> None:
    with pytest.raises(LeagueError, match="only a head-to-head race"):
        record_head_to_head(league, replace(race, rules=DEFAULT_RULES))
    with pytest.raises(LeagueError, match="there is no league night"):
        record_head_to_head(league, race, night_id="01M8NYZGRM59PJDYMJKX91NMYP")
    with pytest.raises(LeagueError, match="is not a bracket match of a night"):
        record_head_to_head(league, race, match_id="W1-1")
    assert league.query_one("SELECT count(*) FROM head_to_heads")[0] == 0


def test_incidents_kept_are_the_first_and_a_record_fits_a_synced_text(
    league: League, race: HeadToHeadResult
) -> None:
    assert MAX_TEXT == MAX_STRING_CHARS  # what one synced text holds
    many = tuple(Incident(float(k), "overtake", 0, 1) for k in range(MAX_INCIDENTS + 50))
    record_head_to_head(league, replace(race, incidents=many))
    row = league.query_one("SELECT incidents, cars FROM head_to_heads")
    kept = json.loads(row["incidents"])
    assert len(kept) == MAX_INCIDENTS and kept[0]["clock"] == 0.0
    assert len(row["incidents"]) <= MAX_TEXT and len(row["cars"]) <= MAX_TEXT


def test_a_race_too_long_for_one_record_is_refused_in_a_sentence(
    league: League, race: HeadToHeadResult
) -> None:
    first = race.cars[0]
    lap = first.result.laps[0]
    laps = tuple(replace(lap, number=n) for n in range(1, 700))
    long_car = replace(first, laps_completed=len(laps), result=replace(first.result, laps=laps))
    with pytest.raises(LeagueError, match="more than one shared record holds"):
        record_head_to_head(league, replace(race, cars=(long_car, *race.cars[1:])))


def test_a_lap_list_round_trips_as_a_race_laps_record(race: HeadToHeadResult) -> None:
    for lap in lap_rows(race.cars[0].result):
        assert lap_from_list(lap_list(lap)) == lap
    crashed = {**lap_rows(race.cars[0].result)[0], "crashes": 2}
    assert lap_from_list(lap_list(crashed)) == crashed


def _race(*racers: str) -> RecordedHeadToHead:
    places = tuple(
        CarPlace(position, racer, "m", 3, None, None, 10.0)
        for position, racer in enumerate(racers, start=1)
    )
    return RecordedHeadToHead("id", "t", "2026-11-30", 0, 60.0, places, None, None)


def test_the_board_counts_wins_losses_and_rivals_beaten() -> None:
    races = [
        _race("ana", "bob"),
        _race("bob", "ana"),
        _race("ana", "cy", "bob"),
        _race("cy", "dee"),
    ]
    board = {s.racer: s for s in head_to_head_board(races)}
    assert (board["ana"].starts, board["ana"].wins, board["ana"].losses) == (3, 2, 1)
    assert (board["ana"].beaten, board["ana"].beaten_by) == (3, 1)
    assert (board["bob"].wins, board["bob"].losses, board["bob"].beaten) == (1, 2, 1)
    assert (board["cy"].wins, board["cy"].losses, board["cy"].beaten) == (1, 1, 2)
    assert [s.racer for s in head_to_head_board(races)] == ["ana", "cy", "bob", "dee"]
    assert record_between(races, "ana", "bob") == (2, 1)
    assert record_between(races, "bob", "ana") == (1, 2)
    assert record_between(races, "ana", "dee") == (0, 0)


def test_a_racer_with_two_cars_counts_each_and_meets_others_by_the_better() -> None:
    races = [_race("bob", "ana", "ana")]
    board = {s.racer: s for s in head_to_head_board(races)}
    assert (board["ana"].starts, board["ana"].wins, board["ana"].losses) == (2, 0, 2)
    assert record_between(races, "ana", "bob") == (0, 1)
    assert record_between(races, "bob", "ana") == (1, 0)

"""The head-to-head board both front ends read: ranks over the whole board, each racer's
cars, replayed starts, their record against each rival, and the JSON document."""

from __future__ import annotations

import pytest

from league.head_to_head_board import (
    HEAD_TO_HEAD_COLUMNS,
    head_to_head_json,
    races_of,
    read_head_to_head_board,
    rival_records,
)
from league.head_to_heads import record_head_to_head
from league.report import to_csv
from league.store import League
from sim.race.head_to_head import HeadToHeadResult
from sim.race.rules import Verification
from tests.league.helpers import head_to_head_in_order
from tests.league.sync.leagues import head_to_head


@pytest.fixture(scope="module")
def three_cars() -> HeadToHeadResult:
    return head_to_head("x", "y", "z", seed=1)


@pytest.fixture
def raced(league: League, three_cars: HeadToHeadResult) -> League:
    """ana beats bob twice (once in her second model), bob beats ana once; cy last of
    three behind ana and bob."""
    for racers, models in (
        (("ana", "bob"), ("ana-v1", "bob-car")),
        (("bob", "ana"), ("bob-car", "ana-v2")),
        (("ana", "bob"), ("ana-v2", "bob-car")),
        (("ana", "bob", "cy"), ("ana-v2", "bob-car", "cy-car")),
    ):
        record_head_to_head(league, head_to_head_in_order(three_cars, *racers, models=models))
    return league


def test_ranks_are_the_whole_boards_and_a_racer_named_keeps_theirs(raced: League) -> None:
    board = read_head_to_head_board(raced)
    assert [(row.rank, row.racer, row.wins, row.losses) for row in board.rows] == [
        (1, "ana", 3, 1),
        (2, "bob", 1, 3),
        (3, "cy", 0, 1),
    ]
    ana = board.rows[0]
    assert ana.cars == ("ana-v2", "ana-v1")  # the model of most starts first
    assert (ana.starts, ana.beaten, ana.beaten_by, ana.replayed_starts) == (4, 4, 1, 0)
    [cy] = read_head_to_head_board(raced, racer="cy").rows
    assert cy.rank == 3 and cy.beaten_by == 2


def test_each_rival_record_counts_the_races_both_were_in(raced: League) -> None:
    board = read_head_to_head_board(raced)
    assert [(r.rival, r.wins, r.losses) for r in rival_records(board, "ana")] == [
        ("bob", 3, 1),
        ("cy", 1, 0),
    ]
    assert [(r.rival, r.wins, r.losses) for r in rival_records(board, "cy")] == [
        ("ana", 0, 1),
        ("bob", 0, 1),
    ]
    assert len(races_of(board, "ana")) == 4 and len(races_of(board, "cy")) == 1


def test_a_board_of_replayed_races_counts_none_until_one_is_replayed(raced: League) -> None:
    replayed = read_head_to_head_board(raced, verification=Verification.REPLAYED)
    assert replayed.rows == [] and replayed.races == []
    everything = read_head_to_head_board(raced)
    assert {standing.standing for standing in everything.standings.values()} == {"verifiable"}


def test_the_json_document_and_the_csv_share_the_rows(raced: League) -> None:
    board = read_head_to_head_board(raced)
    document = head_to_head_json(board, "beginner-oval")
    assert document["board"] == "head-to-head" and document["races"] == 4
    assert document["track"] == "beginner-oval"
    assert document["rows"][0] == {
        "rank": 1,
        "racer": "ana",
        "cars": ["ana-v2", "ana-v1"],
        "starts": 4,
        "wins": 3,
        "losses": 1,
        "rivals_beaten": 4,
        "beaten_by": 1,
        "replayed_starts": 0,
        "hand_timed_starts": 0,
    }
    lines = to_csv(HEAD_TO_HEAD_COLUMNS, board.rows).splitlines()
    assert lines[0] == "rank,racer,car,wins,losses,ahead of,behind,replayed"
    assert lines[1] == "1,ana,ana-v2 (+1),3,1,4,1,0 of 4"

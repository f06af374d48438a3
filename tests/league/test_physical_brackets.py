"""A bracket of physical cars: the night's hand-timed qualifiers seed it, each match is
timed by hand for both cars at once (league.timekeeper.match), and the recorded matches
decide it as simulated ones do, said to be timed by hand."""

from __future__ import annotations

from dataclasses import replace

import pytest

from league import nights
from league.bracket_nights import (
    bracket_is_physical,
    draw_night_bracket,
    left_out_note,
    next_match,
    record_match,
)
from league.bracket_records import bracket_places, read_bracket
from league.errors import LeagueError
from league.head_to_heads import TABLE
from league.races import record_race
from league.records import record_body
from league.store import League
from league.timekeeper.car import car_name
from league.timekeeper.match import MatchCar, TimekeptMatch
from league.trust.replay import replay_setup
from sim.physics.labels import PHYSICAL
from sim.race.head_to_head import HeadToHeadResult
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result
from tests.league.test_nights import FakeEngine, _resolve

MATCH_RULES = replace(HEAD_TO_HEAD_RULES, lap_count=2)
# Hand-timed qualifying laps: red is quickest, then blue, green, pink.
PHYSICAL_CARS = {"ana": ("red", 10.0), "bob": ("blue", 10.5), "cat": ("green", 11.0)}
PHYSICAL_CARS["dan"] = ("pink", 11.5)


def physical_night(league: League) -> nights.Night:
    night = nights.new_night(league, resolve_track(TRACK), rules=RaceRules(), name="Garage")
    for racer, (car, _) in PHYSICAL_CARS.items():
        nights.add_entrant(league, night, racer, f"physical:{car}")
    for racer in ("eve", "fay"):
        nights.add_entrant(league, night, racer, "reference")
    nights.draw_heats(league, night, seed=3)
    laps = {"eve": [12.0], "fay": [12.5]}
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(laps))
    for heat in nights.heats(league, night):
        if heat.race_id is None:
            car, lap = PHYSICAL_CARS[heat.entrant.racer]
            timed = replace(
                race_result(heat.entrant.racer, [lap]), physics=PHYSICAL, model_name=car
            )
            record_race(league, timed, night.id, heat_id=heat.id)
    return night


def timed_match(first: str, second: str, winner: str) -> HeadToHeadResult:
    """Two laps each, hand-timed: the winner's in 10 s, the other's in 12 s."""
    match = TimekeptMatch(MATCH_RULES)
    match.start_or_pause(0.0)
    grid = [first, second]
    for lap in (1, 2):
        for k, racer in enumerate(grid):
            match.capture(k, lap * (10.0 if racer == winner else 12.0))
    cars = [
        MatchCar(racer, car_name(f"physical:{PHYSICAL_CARS[racer][0]}"), "physical-" + racer)
        for racer in grid
    ]
    return match.result(resolve_track(TRACK), cars)


def test_a_physical_bracket_is_timed_by_hand_to_its_champion(league: League) -> None:
    night = physical_night(league)
    with pytest.raises(LeagueError, match=r"has 4, simulated cars left out \(eve, fay\)"):
        draw_night_bracket(league, night, size=5, rules=MATCH_RULES, physical=True)
    drawn = draw_night_bracket(league, night, rules=MATCH_RULES, physical=True)
    assert [drawn.racers[e] for e in drawn.bracket.seeds] == ["ana", "bob", "cat", "dan"]
    assert bracket_is_physical(league, night)
    assert left_out_note(league, night).startswith(
        "Simulated cars are left out of the bracket (eve, fay are)"
    )

    # Cat knocks bob out, then beats ana in the final.
    winners = {("ana", "dan"): "ana", ("bob", "cat"): "cat", ("ana", "cat"): "cat"}
    while (cars := next_match(league, night)) is not None:
        assert cars.physical
        first, second = cars.first.racer, cars.second.racer
        result = timed_match(first, second, winners[(first, second)])
        record_match(league, night, cars.match.id, result)

    decided = read_bracket(league, night.id)
    assert decided is not None
    assert bracket_places(league, [night.id])[night.id][:2] == ["cat", "ana"]
    # Each match is a head-to-head record timed by hand: never said to be verified by replay.
    for race_id in [race.id for race in decided.races.values()]:
        body = record_body(league, TABLE, race_id)
        assert body["physics"] == PHYSICAL
        assert replay_setup(body) == "its laps were timed by hand on a real track"


def test_a_simulated_match_result_is_not_a_physical_match(league: League) -> None:
    """A match is recorded only with its own two entrants; a bracket of the simulated cars
    is still the default, the physical cars left out."""
    night = physical_night(league)
    drawn = draw_night_bracket(league, night, rules=MATCH_RULES)
    assert [drawn.racers[e] for e in drawn.bracket.seeds] == ["eve", "fay"]
    assert not bracket_is_physical(league, night)
    cars = next_match(league, night)
    assert cars is not None and not cars.physical
    with pytest.raises(LeagueError, match="this race's cars are ana, bob"):
        record_match(league, night, cars.match.id, timed_match("ana", "bob", "ana"))


def test_a_physical_car_is_named_so_on_the_head_to_head_board(league: League) -> None:
    """Named as the lap boards name it, and its starts counted as timed by hand, never as
    starts a replay has yet to check."""
    from league.head_to_head_board import (
        HEAD_TO_HEAD_COLUMNS,
        cars_cell,
        head_to_head_json,
        read_head_to_head_board,
    )
    from racer_tui.app.widgets.head_to_head_board import describe_racer

    night = physical_night(league)
    draw_night_bracket(league, night, size=2, rules=MATCH_RULES, physical=True)
    cars = next_match(league, night)
    assert cars is not None
    record_match(league, night, cars.match.id, timed_match("ana", "bob", "bob"))
    board = read_head_to_head_board(league, night_id=night.id)
    assert [(row.racer, cars_cell(row)) for row in board.rows] == [
        ("bob", "blue (physical)"),
        ("ana", "red (physical)"),
    ]
    replayed = next(column for column in HEAD_TO_HEAD_COLUMNS if column.title == "replayed")
    assert [replayed.cell(row) for row in board.rows] == ["hand-timed", "hand-timed"]
    assert [row["hand_timed_starts"] for row in head_to_head_json(board, None)["rows"]] == [1, 1]
    detail = describe_racer(board, board.rows[0], {}, {}).plain
    assert "1 start hand-timed (physical cars are not replayed)" in detail
    assert "replayed here" not in detail

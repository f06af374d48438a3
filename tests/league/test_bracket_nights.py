"""A bracket night: time-trial heats qualify, the standings seed a knock-out bracket, real
head-to-head races decide its matches, and its final order is the night's places and the
season's points."""

from __future__ import annotations

from dataclasses import replace

import pytest

from league import nights
from league.bracket_nights import draw_night_bracket, next_match, record_match
from league.bracket_records import bracket_places, read_bracket, store_bracket
from league.brackets import Format
from league.errors import LeagueError
from league.seasons import new_season, season_standings
from league.store import League
from sim.race.driver import reference_driver
from sim.race.head_to_head import Entry, HeadToHeadResult, run_head_to_head
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK
from tests.league.test_nights import FakeEngine, _resolve

# Qualifying: dee is quickest, then cy, bob, ana (seeds 1-4); eve sets no lap.
QUALIFYING = {
    "ana": [12.0, 12.0],
    "bob": [11.5, 11.6],
    "cy": [11.0, 11.2],
    "dee": [10.5, 10.9],
    "eve": [],
}
MATCH_RULES = replace(HEAD_TO_HEAD_RULES, lap_count=1)


def qualified_night(league: League, season: str | None = None) -> nights.Night:
    night = nights.new_night(
        league, resolve_track(TRACK), rules=RaceRules(), name="Bracket night", season=season
    )
    for racer in QUALIFYING:
        nights.add_entrant(league, night, racer, "reference")
    nights.draw_heats(league, night, seed=3)
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(QUALIFYING))
    return night


def raced(first: str, second: str, *, winner: str, seed: int = 1) -> HeadToHeadResult:
    """A real one-lap head-to-head race of the two racers' reference cars, `winner` first
    past the line (the reference driver against itself: the front of the grid wins)."""
    track = resolve_track(TRACK)
    driver = reference_driver(track)
    grid = [winner, second if winner == first else first]
    result = run_head_to_head(track, MATCH_RULES, [Entry(r, driver) for r in grid], seed=seed)
    assert result.cars[0].result.racer == winner  # the car in front stays in front
    return result


def race_next(league: League, night: nights.Night, winner_seed: str) -> str:
    """Race the next match with the racer `winner_seed` winning it (the higher or the
    lower seed of the two); the match's id."""
    cars = next_match(league, night)
    assert cars is not None
    first, second = cars.first.racer, cars.second.racer
    winner = first if winner_seed == "higher" else second
    record_match(league, night, cars.match.id, raced(first, second, winner=winner))
    return cars.match.id


def test_qualifying_seeds_the_bracket_and_the_final_order_gives_the_points(
    league: League,
) -> None:
    season = new_season(league, "Spring", points=(10, 6, 4, 2, 1))
    night = qualified_night(league, season=season.name)
    drawn = draw_night_bracket(league, night, rules=MATCH_RULES)
    # The standings seed it, best first; eve set no counting lap, so she did not qualify.
    assert [drawn.racers[e] for e in drawn.bracket.seeds] == ["dee", "cy", "bob", "ana"]
    cars = next_match(league, night)
    assert cars is not None
    assert (cars.match.id, cars.first.racer, cars.second.racer) == ("W1-1", "dee", "ana")
    # The qualifying is over: no more entrants or draws.
    with pytest.raises(LeagueError, match="bracket drawn"):
        nights.add_entrant(league, night, "fay", "reference")
    # A race of the wrong cars, or of a match not ready, is refused.
    with pytest.raises(LeagueError, match="match W1-1 is ana v dee"):
        record_match(league, night, "W1-1", raced("dee", "bob", winner="dee"))
    with pytest.raises(LeagueError, match="cannot be raced yet"):
        record_match(league, night, "W2-1", raced("dee", "cy", winner="dee"))

    # The semi-finals: ana beats dee (an upset), cy beats bob; the final: cy beats ana.
    assert race_next(league, night, "lower") == "W1-1"
    with pytest.raises(LeagueError, match="W1-1 of league night 'Bracket night' is raced"):
        record_match(league, night, "W1-1", raced("dee", "ana", winner="dee", seed=2))
    with pytest.raises(LeagueError, match="bracket matches still to race"):
        nights.close_night(league, night, "host")
    assert race_next(league, night, "higher") == "W1-2"
    assert race_next(league, night, "higher") == "W2-1"  # cy, seed 2, over ana, seed 4
    assert next_match(league, night) is None

    drawn_after = read_bracket(league, night.id)
    assert drawn_after is not None
    order = drawn_after.final_order()
    assert order is not None
    assert [drawn_after.racers[e] for e in order] == ["cy", "ana", "dee", "bob"]
    # The night's places are the bracket's, then the racers who did not qualify.
    placed = nights.close_night(league, night, "host")
    assert [(s.entry.racer, s.position, s.points) for s in placed] == [
        ("cy", 1, 10),
        ("ana", 2, 6),
        ("dee", 3, 4),
        ("bob", 4, 2),
        ("eve", None, 0),
    ]
    assert [(s.racer, s.points) for s in season_standings(league, season)][:4] == [
        ("cy", 10),
        ("ana", 6),
        ("dee", 4),
        ("bob", 2),
    ]


def test_a_bracket_is_drawn_only_once_the_qualifying_is_over(league: League) -> None:
    night = nights.new_night(league, resolve_track(TRACK), rules=RaceRules(), name="Early")
    for racer in ("ana", "bob"):
        nights.add_entrant(league, night, racer, "reference")
    with pytest.raises(LeagueError, match="still qualifying"):
        draw_night_bracket(league, night, rules=MATCH_RULES)
    with pytest.raises(LeagueError, match="no bracket"):
        next_match(league, night)


def test_a_bracket_of_a_chosen_size_takes_the_best_qualifiers(league: League) -> None:
    night = qualified_night(league)
    with pytest.raises(LeagueError, match="a bracket of 5 needs 5 racers"):
        draw_night_bracket(league, night, size=5, rules=MATCH_RULES)
    with pytest.raises(LeagueError, match="head-to-head rules"):
        draw_night_bracket(league, night, size=2, rules=RaceRules())
    drawn = draw_night_bracket(league, night, size=2, format=Format.DOUBLE, rules=MATCH_RULES)
    assert [drawn.racers[e] for e in drawn.bracket.seeds] == ["dee", "cy"]
    with pytest.raises(LeagueError, match="drawn already"):
        draw_night_bracket(league, night, size=2, rules=MATCH_RULES)
    # Double elimination of two: cy wins their first race, dee the grand final (both have
    # lost once), and the deciding race decides.
    race_next(league, night, "lower")
    race_next(league, night, "higher")  # GF: dee (from the losers' side) beats cy
    assert next_match(league, night) is not None  # both have lost once: the decider
    race_next(league, night, "higher")
    drawn = read_bracket(league, night.id)
    assert drawn is not None and drawn.final_order() is not None


def test_a_bracket_naming_another_nights_entrants_seats_nobody(league: League) -> None:
    """A record made elsewhere can name any entrant ids: only the night's own are seated,
    so no race can count for a match of strangers and the night keeps its own places."""
    night = qualified_night(league)
    other = nights.new_night(league, resolve_track(TRACK), rules=RaceRules(), name="Other")
    seeds = [entrant.id for entrant in nights.entrants(league, night)[:2]]
    with league.transaction():
        store_bracket(league, other.id, seeds, Format.SINGLE, MATCH_RULES)
    drawn = read_bracket(league, other.id)
    assert drawn is not None and drawn.racers == {}
    assert bracket_places(league, [other.id]) == {}
    with pytest.raises(LeagueError, match="lost an entrant"):
        next_match(league, other)


def test_the_higher_seed_starts_in_front_in_every_round(league: League) -> None:
    """The host walk: a losers' round put the lower seed at the front of the grid, where
    the car of one pace wins."""
    night = qualified_night(league)
    drawn = draw_night_bracket(league, night, format=Format.DOUBLE, rules=MATCH_RULES)
    seed = {drawn.racers[entrant]: rank for rank, entrant in enumerate(drawn.bracket.seeds)}
    raced = 0
    while (cars := next_match(league, night)) is not None:
        assert seed[cars.first.racer] < seed[cars.second.racer], cars.match.id
        # The lower seed wins every other race, so the losers' rounds mix the seeds.
        race_next(league, night, "lower" if raced % 2 == 0 else "higher")
        raced += 1
    assert raced >= 6  # a double elimination of four: winners', losers' rounds, finals


def test_physical_cars_are_left_out_of_a_bracket_and_the_host_is_told(league: League) -> None:
    """The host walk: a physical car topping the qualifying made every bracket impossible,
    and the sentence's way out (a smaller bracket) could not work."""
    from league.bracket_nights import left_out_note
    from league.races import record_race
    from sim.physics.labels import PHYSICAL
    from tests.league.helpers import race_result

    night = nights.new_night(league, resolve_track(TRACK), rules=RaceRules(), name="Mixed")
    for racer in ("ana", "bob", "cy"):
        nights.add_entrant(league, night, racer, "reference")
    nights.add_entrant(league, night, "cat", "physical:blue")
    nights.draw_heats(league, night, seed=3)
    laps = {"ana": [12.0], "bob": [11.5], "cy": [11.0]}
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(laps))
    [cat] = [heat for heat in nights.heats(league, night) if heat.race_id is None]
    timed = replace(race_result("cat", [9.0]), physics=PHYSICAL, model_name="blue")
    record_race(league, timed, night.id, heat_id=cat.id)  # the quickest qualifier
    with pytest.raises(LeagueError, match=r"has 3, physical cars left out \(cat\)"):
        draw_night_bracket(league, night, size=4, rules=MATCH_RULES)
    drawn = draw_night_bracket(league, night, rules=MATCH_RULES)
    assert [drawn.racers[e] for e in drawn.bracket.seeds] == ["cy", "bob", "ana"]
    note = left_out_note(league, night)
    assert note.startswith("Physical cars are left out of the bracket (cat is)")

"""A head-to-head race crosses machines as one signed record: the organiser's lands whole on
every machine; a racer's is refused (it names other racers' results), in one sentence."""

from __future__ import annotations

from dataclasses import replace

from league import nights
from league.bracket_nights import draw_night_bracket, record_match
from league.bracket_records import read_bracket, store_bracket
from league.brackets import Format
from league.head_to_heads import head_to_head_races, record_head_to_head
from league.records import record_body
from sim.race.rules import HEAD_TO_HEAD_RULES
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK
from tests.league.sync.leagues import NIGHT_LAPS, RULES, _fake_engine, head_to_head
from tests.league.sync.test_signed_results import Machine


def test_the_organisers_race_lands_whole_on_every_machine(
    organiser_ana_viewer: dict[str, Machine],
) -> None:
    organiser, ana, viewer = (
        organiser_ana_viewer["organiser"],
        organiser_ana_viewer["ana"],
        organiser_ana_viewer["viewer"],
    )
    race = head_to_head("ana", "bob", seed=4)
    record_head_to_head(organiser.league, race)
    assert organiser.sync().pushed >= 1
    for machine in (ana, viewer):
        machine.sync()
        assert machine.quarantine() == {}
        assert head_to_head_races(machine.league) == head_to_head_races(organiser.league)
        assert record_body(machine.league, "head_to_heads", race.race_id) == record_body(
            organiser.league, "head_to_heads", race.race_id
        )


def test_a_racers_race_is_refused_on_every_other_machine(
    organiser_ana_viewer: dict[str, Machine],
) -> None:
    ana, viewer = organiser_ana_viewer["ana"], organiser_ana_viewer["viewer"]
    race = head_to_head("ana", "bob", seed=5)
    record_head_to_head(ana.league, race)
    ana.sync()
    viewer.sync()
    assert head_to_head_races(viewer.league) == []
    reasons = viewer.quarantine()
    [reason] = [text for where, text in reasons.items() if race.race_id in where]
    assert reason == "it is signed by racer ana, but only an organiser makes a head-to-head race"


def test_a_bracket_night_lands_whole_with_its_places(
    organiser_ana_viewer: dict[str, Machine],
) -> None:
    """The organiser's bracket and its match cross as signed records: every machine seeds
    the same bracket, counts the same winner and places the night the same."""
    organiser, viewer = organiser_ana_viewer["organiser"], organiser_ana_viewer["viewer"]
    night = nights.new_night(organiser.league, resolve_track(TRACK), rules=RULES, name="Cup")
    for racer in NIGHT_LAPS:
        nights.add_entrant(organiser.league, night, racer, "reference")
    nights.draw_heats(organiser.league, night, seed=1)
    nights.run_heats(
        organiser.league, night, resolve_track(TRACK), lambda spec, _: spec, run_race=_fake_engine
    )
    drawn = draw_night_bracket(
        organiser.league, night, size=2, rules=replace(HEAD_TO_HEAD_RULES, lap_count=1)
    )
    first, second = (drawn.racers[entrant] for entrant in drawn.bracket.seeds)
    record_match(organiser.league, night, "W1-1", head_to_head(second, first, seed=6))  # upset
    organiser.sync()
    viewer.sync()
    assert viewer.quarantine() == {}
    pulled = read_bracket(viewer.league, night.id)
    assert pulled is not None and pulled.final_order() == list(drawn.bracket.seeds[::-1])
    placed = [
        s.entry.racer
        for s in nights.standings(viewer.league, nights.get_night(viewer.league, night.id))
    ]
    assert placed[:2] == [second, first]


def test_a_racers_bracket_is_refused(organiser_ana_viewer: dict[str, Machine]) -> None:
    organiser, ana, viewer = (
        organiser_ana_viewer["organiser"],
        organiser_ana_viewer["ana"],
        organiser_ana_viewer["viewer"],
    )
    night = nights.new_night(organiser.league, resolve_track(TRACK), rules=RULES, name="Cup")
    organiser.sync()
    ana.sync()
    with ana.league.transaction():
        store_bracket(
            ana.league,
            night.id,
            ["01M7YFZPX152TMAJ036HERQM71", "01M7YFZPX152TMAJ036HERQM72"],
            Format.SINGLE,
            HEAD_TO_HEAD_RULES,
        )
    ana.sync()
    viewer.sync()
    assert read_bracket(viewer.league, night.id) is None
    reasons = viewer.quarantine()
    assert any("only an organiser makes a bracket" in text for text in reasons.values())

"""A head-to-head race crosses machines as one signed record: the organiser's lands whole on
every machine; a racer's is refused (it names other racers' results), in one sentence."""

from __future__ import annotations

from league.head_to_heads import head_to_head_races, record_head_to_head
from league.records import record_body
from tests.league.sync.leagues import head_to_head
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

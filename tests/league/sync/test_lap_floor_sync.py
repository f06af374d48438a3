"""The issue's two forgeries of lap times, pushed by a script with the racer's own key past
racer-tui's own refusals: a race of 4.100 s laps and a submission of a 3.900 s (or
1.000 s) lap on re:Invent 2018. Neither reaches the organiser's board nor a fresh
machine's, on either kind of store; each is in quarantine naming the lap and the floor."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from league.records import record_body
from league.submissions import submit_model
from league.sync.record import make_record
from league.sync.stores import open_store
from league.trust import membership
from league.trust.seals import make_seal
from sim.coach.plausible import fastest_possible_lap
from sim.foundation.ids import new_id
from sim.tracks.catalog import resolve_track
from tests.league.helpers import model_folder
from tests.league.sync.conftest import QUICK_RETRY, StoreFactory
from tests.league.sync.test_signed_results import Machine

REINVENT = "reinvent_base"


@pytest.fixture
def league_of_three(
    store_url: str, open_racer_store: StoreFactory, tmp_path: Path
) -> Iterator[dict[str, Machine]]:
    """The organiser, racer ana (admitted, one honest race) and a fresh machine."""
    made = {name: Machine(tmp_path, name, store_url) for name in ("organiser", "ana", "fresh")}
    organiser, ana = made["organiser"], made["ana"]
    membership.found_league(organiser.league, organiser.key)
    organiser.sync()
    ana.race("ana", [12.0, 11.8])
    ana.sync()
    organiser.sync()
    membership.admit(organiser.league, organiser.key, "ana")
    organiser.sync()
    yield made
    for machine in made.values():
        machine.league.close()


def _push_signed_copy(
    ana: Machine, kind: str, table: str, record_id: str, laps: list[dict[str, Any]]
) -> str:
    """A new record of ana's, like `record_id` but with `laps`, sealed with ana's own key
    and pushed as a script of racer-tui's own functions would."""
    body = record_body(ana.league, table, record_id)
    body["laps"] = laps
    forged = make_record(kind, new_id(), body)
    with open_store(ana.url, retry=QUICK_RETRY) as store:
        store.push([forged.sealed(make_seal(forged, ana.key))])
    return forged.record_id


def _refused_everywhere(made: dict[str, Machine], where: str, sentence: str) -> None:
    for name in ("organiser", "fresh"):
        machine = made[name]
        machine.sync()
        assert min(machine.board().values()) > 11.0, name  # nobody shows the forged lap
        reason = machine.quarantine()[where]
        assert reason.startswith(sentence), (name, reason)


def test_a_race_signed_with_4_100_s_laps_reaches_no_board(
    league_of_three: dict[str, Machine],
) -> None:
    ana = league_of_three["ana"]
    (honest,) = [row[0] for row in ana.league.query("SELECT id FROM races")]
    laps = [
        {**lap, "time_seconds": 4.1, "raw_seconds": 4.1, "penalty_seconds": 0.0}
        for lap in record_body(ana.league, "races", honest)["laps"]
    ]
    forged = _push_signed_copy(ana, "race", "races", honest, laps)
    floor = fastest_possible_lap(resolve_track("hairpin-circuit"))
    sentence = (
        f"its lap 1 of 4.100 s is faster than any car can go round that track (no lap under "
        f"{floor:.3f} s is possible there"
    )
    _refused_everywhere(league_of_three, f"race {forged}", sentence)


@pytest.mark.parametrize("forged_lap", [3.9, 1.0])
def test_a_hand_edited_evaluation_pushed_by_a_script_reaches_no_board(
    league_of_three: dict[str, Machine], tmp_path: Path, forged_lap: float
) -> None:
    ana = league_of_three["ana"]
    folder = model_folder(tmp_path / "garage", laps=(12.4, 12.9), track=REINVENT)
    _, outcome = submit_model(ana.league, str(folder), "ana")
    honest = record_body(ana.league, "submissions", outcome.submission_id)["laps"]
    laps = [{**honest[0], "time_seconds": forged_lap}, *honest[1:]]
    forged = _push_signed_copy(ana, "submission", "submissions", outcome.submission_id, laps)
    floor = fastest_possible_lap(resolve_track(REINVENT))
    sentence = (
        f"its lap 1 of {forged_lap:.3f} s is faster than any car can go round that track (no "
        f"lap under {floor:.3f} s is possible there: under DeepRacer's rules at 4 m/s)"
    )
    _refused_everywhere(league_of_three, f"submission {forged}", sentence)

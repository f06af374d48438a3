"""Head-to-head races are verified by replay as races are: re-run from every car's model,
the grid, the track, the rules and the seed, a true race finishes in the order and with
the laps it claims; a forged one is withdrawn into quarantine; one whose car's model is
not here is unverifiable, with the reason."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from league.head_to_heads import TABLE, head_to_head_races, record_head_to_head
from league.store import League
from league.trust.head_to_head_replay import verify_head_to_heads
from racer_tui.cli.main import main
from sim.race.driver import Driver
from sim.race.head_to_head import HeadToHeadResult
from sim.tracks.track import Track
from sim.training.drivers import DriversByHash
from tests.league.sync.leagues import head_to_head


def _swapped(race: HeadToHeadResult) -> HeadToHeadResult:
    """The race as its loser would like it told: the first two cars' places swapped."""
    first, second, *rest = race.cars
    return replace(
        race,
        cars=(replace(second, position=1), replace(first, position=2), *rest),
    )


def _quicker(race: HeadToHeadResult) -> HeadToHeadResult:
    """The winner's first lap claimed 0.3 s quicker than it was driven."""
    winner = race.cars[0]
    lap = winner.result.laps[0]
    quick = replace(lap, time_seconds=lap.time_seconds - 0.3, raw_seconds=lap.raw_seconds - 0.3)
    laps = (quick, *winner.result.laps[1:])
    return replace(
        race, cars=(replace(winner, result=replace(winner.result, laps=laps)), *race.cars[1:])
    )


def test_a_true_race_verifies_and_forged_ones_are_withdrawn(league: League) -> None:
    honest = head_to_head("ana", "bob", seed=3)
    driven = head_to_head("cy", "dee", seed=4)
    swapped = _swapped(driven)
    quicker = _quicker(head_to_head("eve", "fay", seed=5))
    for race in (honest, swapped, quicker):
        record_head_to_head(league, race)

    verdicts = {v.race_id: v for v in verify_head_to_heads(league, DriversByHash())}

    assert verdicts[honest.race_id].outcome == "same"
    in_order = " v ".join(car.result.racer for car in honest.cars)
    assert verdicts[honest.race_id].racer == in_order
    assert verdicts[swapped.race_id].outcome == "differs"
    first, second = (car.car + 1 for car in driven.cars)
    assert verdicts[swapped.race_id].detail == (
        f"re-run here, car {first} finishes first and the order is car {first}, car {second}, "
        f"not the car {second}, car {first} it claims"
    )
    assert verdicts[quicker.race_id].outcome == "differs"
    assert "its lap 1 has" in verdicts[quicker.race_id].detail
    assert [race.id for race in head_to_head_races(league)] == [honest.race_id]
    quarantined = {
        row["record_id"]: row["reason"]
        for row in league.query("SELECT record_id, reason FROM sync_quarantine")
    }
    assert set(quarantined) == {swapped.race_id, quicker.race_id}
    assert quarantined[quicker.race_id].startswith("it is the head-to-head race ")
    # Verified once: a second run re-races nothing.
    assert verify_head_to_heads(league, DriversByHash()) == []
    [again] = verify_head_to_heads(league, DriversByHash(), again=True)
    assert again.outcome == "same"


def test_a_race_whose_model_is_not_here_is_unverifiable(league: League) -> None:
    race = head_to_head("ana", "bob", seed=6)
    record_head_to_head(league, race)

    def nothing_here(model_hash: str, track: Track) -> Driver | None:
        return None

    [verdict] = verify_head_to_heads(league, nothing_here)
    assert verdict.outcome == "unverifiable"
    assert (
        "car 1's model reference:" in verdict.detail and "is not in this garage" in verdict.detail
    )
    assert league.query_one(f"SELECT count(*) FROM {TABLE}")[0] == 1  # kept: nothing disproved
    row = league.query_one("SELECT outcome FROM sync_replays WHERE race_id = ?", (race.race_id,))
    assert row["outcome"] == "unverifiable"
    assert json.loads(league.query_one(f"SELECT cars FROM {TABLE}")["cars"])


def test_sync_verify_re_runs_a_recorded_head_to_head_race(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = str(tmp_path / "league.db")
    race = ("--race", "reference", "reference", "--rules", "head-to-head", "--laps", "1")
    assert main([*race, "--track", "hairpin-circuit", "--record", "--db", db, "--json"]) == 0
    [race_id] = json.loads(capsys.readouterr().out)["recorded"]
    assert main(["sync", "verify", "--db", db, "--json"]) == 0
    [verdict] = json.loads(capsys.readouterr().out)
    assert (verdict["race_id"], verdict["outcome"]) == (race_id, "same")
    assert verdict["racer"] == "reference v reference"
    assert main(["sync", "verify", "--db", db]) == 0
    assert "Re-ran 0 races" in capsys.readouterr().out  # verified once is enough

"""Verification by replay of head-to-head races (league.head_to_heads), as races are
verified (league.trust.replay): a record names every car's model hash, its grid slot, the
track, the rules and the seed, and a head-to-head race is deterministic, so a machine that
holds every car's model races it again and compares.

The cars must finish in the order claimed, each with the laps claimed. A race that comes
out otherwise was not driven as it claims: it is taken out of the league and held in
quarantine with the first difference. A race that cannot be re-run here (a car's model is
not on this machine, its track is not, another simulator timed it, or a car's policy
computed with another machine's numerics) is unverifiable here and says why. Verdicts are
remembered with races' (`sync_replays`, by record id and content).
"""

from __future__ import annotations

import json
from collections.abc import Collection, Sequence
from typing import Any

from league.head_to_heads import TABLE, lap_from_list
from league.records import record_body
from league.store import League
from league.sync import incoming
from league.sync.local import STORE_SETTING, get_setting
from league.sync.record import Seal, SyncRecord
from league.trust.replay import (
    DriverFor,
    Verdict,
    cannot_rerun,
    compare_laps,
    remember,
    replay_setup,
    unverified,
)
from league.trust.standing import other_numerics
from sim.race.driver import Driver, driver_under
from sim.race.head_to_head import Entry, run_head_to_head

KIND = "head_to_head"


def racers_of(cars: Sequence[dict[str, Any]]) -> str:
    """ "ana v bob": the race's racers in finishing order, as a verdict names it."""
    return " v ".join(str(car["racer"]) for car in cars)


def verify_head_to_heads(
    league: League,
    driver_for: DriverFor,
    *,
    again: bool = False,
    ids: Collection[str] | None = None,
) -> list[Verdict]:
    """Re-run every head-to-head race not verified before (`again`: every one; `ids`:
    only these) and judge it."""
    verdicts = []
    for race_id, digest in unverified(league, TABLE, again, ids):
        body = record_body(league, TABLE, race_id)
        verdict = _verify(race_id, body, driver_for)
        with league.transaction():
            remember(league, verdict, digest)
            if verdict.outcome == "differs":
                _withdraw(league, verdict, body, digest)
        verdicts.append(verdict)
    return verdicts


def _verify(race_id: str, body: dict[str, Any], driver_for: DriverFor) -> Verdict:
    cars = json.loads(body["cars"])
    racers = racers_of(cars)

    def unverifiable(why: str, remedy: str = "") -> Verdict:
        return cannot_rerun(race_id, racers, why, remedy)

    setup = replay_setup(body)
    if isinstance(setup, str):
        return unverifiable(setup)
    track, rules = setup
    drivers: dict[str, Driver] = {}  # one driver per model: it acts for its cars together
    drivers_then: dict[tuple[str, str], Driver] = {}  # by model and recorded runtime
    entries: list[Entry] = []
    for car in sorted(cars, key=lambda car: int(car["car"])):
        model = str(car["model_hash"])
        if model not in drivers:
            try:
                found = driver_for(model, track)
            except ValueError as error:  # here but cannot drive (its one sentence)
                return unverifiable(str(error))
            if found is None:
                return unverifiable(
                    f"car {car['car'] + 1}'s model {model[:12]} is not in this garage",
                    " (racer-tui sync fetch-bundle installs it, if its racer shared it)",
                )
            drivers[model] = found
        driver = drivers[model]
        recorded, here = str(car.get("runtime") or ""), str(getattr(driver, "runtime", ""))
        if recorded:  # judged only under the runtime that drove it, as a time trial is
            if (model, recorded) not in drivers_then:
                found_then = driver_under(driver, recorded)
                if found_then is None:
                    return unverifiable(other_numerics(recorded, here))
                drivers_then[model, recorded] = found_then
            # One driver per model and runtime: a model's cars act in one batch, as they
            # did when the race was driven.
            driver = drivers_then[model, recorded]
        entries.append(Entry(str(car["racer"]), driver))
    result = run_head_to_head(track, rules, entries, seed=int(body["seed"]))
    order, claimed_order = [c.car for c in result.cars], [int(car["car"]) for car in cars]
    if order != claimed_order:
        return Verdict(
            race_id,
            racers,
            "differs",
            f"re-run here, car {order[0] + 1} finishes first and the order is "
            f"{_grid_order(order)}, not the {_grid_order(claimed_order)} it claims",
        )
    driven = {finish.car: finish.result for finish in result.cars}
    for car in cars:
        claimed = [lap_from_list(lap) for lap in car["laps"]]
        outcome, detail = compare_laps(claimed, [lap.to_json() for lap in driven[car["car"]].laps])
        if outcome != "same":
            return Verdict(race_id, racers, outcome, f"car {car['car'] + 1}: {detail}")
    return Verdict(race_id, racers, "same", "")


def _grid_order(order: Sequence[int]) -> str:
    return ", ".join(f"car {car + 1}" for car in order)


def _withdraw(league: League, verdict: Verdict, body: dict[str, Any], digest: str) -> None:
    row = league.query_one(
        "SELECT signer, signature FROM sync_seals WHERE kind = ? AND record_id = ? "
        "AND content_hash = ?",
        (KIND, verdict.race_id, digest),
    )
    record = SyncRecord(KIND, verdict.race_id, digest, body)
    if row is not None:
        record = record.sealed(Seal(str(row[0]), str(row[1])))
    store = get_setting(league, STORE_SETTING) or ""
    reason = f"it is the head-to-head race {verdict.racer}, but {verdict.detail}"
    incoming.withdraw(league, store, record, reason, final=True)

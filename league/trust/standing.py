"""Each result's standing: what this machine can vouch for about its laps.

No central machine produced a result, so a board says of each one whether it was
**replayed** (raced again here from the model, track, rules and seed it names, with the
same laps: league.trust.replay), is **verifiable** (its model is here, in the garage, as
a bundle a racer shared, or the track's reference driver, but it has not been raced again
yet) or is **unverifiable** (nothing here can race it again: its model is on no machine
we know of, it was timed with another physics or by hand on a real track, or it is an
evaluation submitted from files, which names no seed). A standing is this machine's:
another machine with other models may say otherwise.

The garage's model hashes come from the caller (`local_models`), as replay's driver does:
hashing a garage reads its models' weights, which the league package never loads.
"""

from __future__ import annotations

import json
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

from league.store import League
from sim.physics.labels import BEFORE_VERSIONING, CURRENT, PHYSICAL
from sim.race.driver import REFERENCE_NAME
from sim.tracks.catalog import find_track_by_hash


class Standing(StrEnum):
    """A result's standing here; its value is what boards and JSON (`verification`) say."""

    REPLAYED = "replayed"
    VERIFIABLE = "verifiable"
    UNVERIFIABLE = "unverifiable"


@dataclass(frozen=True)
class ResultStanding:
    standing: Standing
    why: str  # a phrase that completes "it is <standing>: ..."


SUBMITTED: Final = ResultStanding(
    Standing.UNVERIFIABLE, "an evaluation submitted from files names no seed to race it again"
)
_REPLAYED: Final = ResultStanding(Standing.REPLAYED, "raced again here with the same laps")
_BY_HAND: Final = ResultStanding(
    Standing.UNVERIFIABLE, "a physical car's laps, timed by hand on a real track"
)


def other_numerics(recorded: str, here: str) -> str:
    """Why a race of another policy runtime is not judged here (league.trust.replay)."""
    return f"its policy ran on the numerics of {recorded} and this machine's are {here or 'none'}"


def result_standings(
    league: League, ids: Iterable[str], local_models: Collection[str] = ()
) -> dict[str, ResultStanding]:
    """The standing of each result (race or submission) in `ids`; `local_models` are the
    content hashes of the models in this machine's garage. An id that is not a race here is
    a submission's (or gone), and unverifiable."""
    wanted = list(dict.fromkeys(ids))
    if not wanted:
        return {}
    rows = league.query(
        "SELECT r.id, r.model_hash, r.track_hash, coalesce(r.physics, ?), v.outcome, "
        "r.runtime, v.runtime FROM races r LEFT JOIN sync_replays v "
        "ON v.race_id = r.id AND v.content_hash = r.content_hash "
        "WHERE r.id IN (SELECT value FROM json_each(?))",
        (BEFORE_VERSIONING, json.dumps(wanted)),
    )
    shared = {str(row[0]) for row in league.query("SELECT DISTINCT model_hash FROM sync_bundles")}
    tracks_here: dict[str, bool] = {}
    found: dict[str, ResultStanding] = {}
    for race_id, model_hash, track_hash, physics, outcome, runtime, runtime_here in rows:
        if track_hash not in tracks_here:
            tracks_here[track_hash] = find_track_by_hash(track_hash) is not None
        if runtime and runtime_here and runtime != runtime_here and outcome != "same":
            # A replay here found the policy's numerics are not this machine's.
            found[race_id] = ResultStanding(
                Standing.UNVERIFIABLE, other_numerics(str(runtime), str(runtime_here))
            )
            continue
        found[race_id] = _race_standing(
            str(model_hash),
            str(track_hash),
            str(physics),
            outcome,
            track_here=tracks_here[track_hash],
            model_here=model_hash in local_models or model_hash in shared,
        )
    return {result_id: found.get(result_id, SUBMITTED) for result_id in wanted}


def _race_standing(
    model_hash: str,
    track_hash: str,
    physics: str,
    outcome: str | None,
    *,
    track_here: bool,
    model_here: bool,
) -> ResultStanding:
    if outcome == "same":
        return _REPLAYED
    if physics == PHYSICAL:
        return _BY_HAND
    if outcome == "differs":  # withdrawn when it was found; kept here only by a newer pull
        return ResultStanding(Standing.UNVERIFIABLE, "raced again here, its laps differ")
    if physics != CURRENT:
        return ResultStanding(
            Standing.UNVERIFIABLE, f"timed with {physics}, and this racer-tui drives {CURRENT}"
        )
    if not track_here:
        return ResultStanding(Standing.UNVERIFIABLE, "its track is not on this machine")
    if model_hash == f"{REFERENCE_NAME}:{track_hash}":
        return ResultStanding(Standing.VERIFIABLE, "the reference driver, not raced again yet")
    if model_here:
        return ResultStanding(Standing.VERIFIABLE, "its model is here, not raced again yet")
    return ResultStanding(
        Standing.UNVERIFIABLE, "its model is not in this garage and no racer shared it"
    )


def head_to_head_standings(
    league: League, ids: Iterable[str], local_models: Collection[str] = ()
) -> dict[str, ResultStanding]:
    """The standing of each head-to-head race in `ids` (league.head_to_heads): replayed when
    a replay here found it the same; else verifiable only if every car could be raced again
    here, and otherwise unverifiable for the first car that cannot."""
    wanted = list(dict.fromkeys(ids))
    if not wanted:
        return {}
    rows = league.query(
        "SELECT h.id, h.cars, h.track_hash, h.physics, v.outcome FROM head_to_heads h "
        "LEFT JOIN sync_replays v ON v.race_id = h.id AND v.content_hash = h.content_hash "
        "WHERE h.id IN (SELECT value FROM json_each(?))",
        (json.dumps(wanted),),
    )
    shared = {str(row[0]) for row in league.query("SELECT DISTINCT model_hash FROM sync_bundles")}
    found: dict[str, ResultStanding] = {}
    for race_id, cars, track_hash, physics, outcome in rows:
        if outcome == "same":
            found[race_id] = _REPLAYED
            continue
        track_here = find_track_by_hash(track_hash) is not None
        by_car = (
            (
                car["car"] + 1,
                _race_standing(
                    str(car["model_hash"]),
                    str(track_hash),
                    str(physics),
                    outcome,
                    track_here=track_here,
                    model_here=car["model_hash"] in local_models or car["model_hash"] in shared,
                ),
            )
            for car in sorted(json.loads(cars), key=lambda car: int(car["car"]))
        )
        slot, first = next(
            ((slot, of_car) for slot, of_car in by_car if of_car.standing is Standing.UNVERIFIABLE),
            (0, None),
        )
        found[race_id] = (
            ResultStanding(first.standing, f"car {slot}: {first.why}")
            if first is not None
            else ResultStanding(
                Standing.VERIFIABLE, "every car's model is here, not raced again yet"
            )
        )
    return {race_id: found[race_id] for race_id in wanted if race_id in found}

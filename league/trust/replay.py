"""Verification by replay: a race record names everything that made it (the model's
hash, the track's hash, the rules, the seed and the simulator's physics), and races are
deterministic, so any machine holding the model can run the race again and compare.

A race whose laps come out differently was not driven as it claims: it is taken out of
the league and held in quarantine with the first lap that differs. A race that cannot
be re-run here (its model or track is not on this machine, it was timed by another
version of the simulator, or its policy computed with numerics this machine does not
have: `sim.training.runtimes`) is unverifiable here and says why: nothing vouches for its
laps but its racer's signature. Each verdict is remembered per race and content
(`sync_replays`), so a second run re-races only what is new or was unverifiable.

The driver comes from the caller (`DriverFor`): running a trained model needs torch,
which the league package never imports.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, Final, Literal

from league.records import record_body
from league.store import League, now_iso
from league.sync import incoming
from league.sync.local import STORE_SETTING, get_setting
from league.sync.record import Seal, SyncRecord
from league.trust.standing import other_numerics
from sim.physics.labels import BEFORE_VERSIONING, CURRENT, PHYSICAL
from sim.race.driver import Driver, driver_under
from sim.race.engine import run_race
from sim.race.rules import RaceRules, RulesError, rules_from_mapping
from sim.tracks.catalog import find_track_by_hash, resolve_track
from sim.tracks.track import Track

# The model hash -> a driver of that exact model on `track`, or None when it is not here;
# ValueError (one sentence) when it is here but cannot drive.
DriverFor = Callable[[str, Track], Driver | None]
Outcome = Literal["same", "differs", "unverifiable"]
OUTCOMES: Final[tuple[Outcome, ...]] = ("same", "differs", "unverifiable")
# Recorded laps are the engine's own floats; anything past this is not rounding.
_TOLERANCE_S: Final = 1e-6


@dataclass(frozen=True)
class Verdict:
    race_id: str
    racer: str
    outcome: Outcome
    detail: str  # one sentence: what differed, or why it is unverifiable ("" when the same)
    runtime_here: str = ""  # this machine's policy runtime, when a policy was run or compared


def verify_races(
    league: League,
    driver_for: DriverFor,
    *,
    again: bool = False,
    race_ids: Collection[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[Verdict]:
    """Re-run every race not verified before (`again`: every race; `race_ids`: only
    these) and judge it."""
    rows = unverified(league, "races", again, race_ids)
    verdicts = []
    for done, (race_id, digest) in enumerate(rows, start=1):
        verdict = _verify(league, race_id, driver_for)
        with league.transaction():
            remember(league, verdict, digest)
            if verdict.outcome == "differs":
                _withdraw(league, verdict, digest)
        verdicts.append(verdict)
        if progress is not None:
            progress(done, len(rows))
    return verdicts


def unverified(
    league: League, table: str, again: bool, ids: Collection[str] | None
) -> list[tuple[str, str]]:
    """(id, content hash) of each row of `table` (races or head-to-head races) not judged
    before, or judged unverifiable (`again`: every row; `ids`: only these), in id order."""
    rows = league.query(
        f"SELECT r.id, r.content_hash FROM {table} r LEFT JOIN sync_replays v "
        "ON v.race_id = r.id AND v.content_hash = r.content_hash "
        "WHERE (? OR v.race_id IS NULL OR v.outcome = 'unverifiable') "
        f"{'' if ids is None else 'AND r.id IN (SELECT value FROM json_each(?))'} "
        "ORDER BY r.id",
        (again,) if ids is None else (again, json.dumps(list(ids))),
    )
    return [(str(row[0]), str(row[1])) for row in rows]


def remember(league: League, verdict: Verdict, digest: str) -> None:
    """Keep `verdict` for the record's content `digest` (call inside a transaction)."""
    league.conn.execute(
        "INSERT INTO sync_replays (race_id, content_hash, outcome, detail, checked_at, "
        "runtime) VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (race_id) DO UPDATE SET "
        "content_hash = excluded.content_hash, outcome = excluded.outcome, "
        "detail = excluded.detail, checked_at = excluded.checked_at, "
        "runtime = excluded.runtime",
        (
            verdict.race_id,
            digest,
            verdict.outcome,
            verdict.detail,
            now_iso(),
            verdict.runtime_here or None,
        ),
    )


def _verify(league: League, race_id: str, driver_for: DriverFor) -> Verdict:
    body = record_body(league, "races", race_id)
    racer = str(body["racer"])

    def unverifiable(why: str, remedy: str = "") -> Verdict:
        return cannot_rerun(race_id, racer, why, remedy)

    setup = replay_setup(body)
    if isinstance(setup, str):
        return unverifiable(setup)
    track, rules = setup
    try:
        driver = driver_for(str(body["model_hash"]), track)
    except ValueError as error:  # the model is here but cannot drive (its one sentence)
        return unverifiable(str(error))
    if driver is None:
        return unverifiable(
            f"its model {str(body['model_hash'])[:12]} is not in this garage",
            " (racer-tui sync fetch-bundle installs it, if its racer shared it)",
        )
    # Another CPU's kernels may turn a near tie between two actions the other way: a race
    # is judged only under the policy runtime that drove it, which may be an earlier
    # version than races take now (races recorded before runtimes were are judged as they
    # always were).
    recorded, here = str(body.get("runtime") or ""), str(getattr(driver, "runtime", ""))
    if recorded:
        driver_then = driver_under(driver, recorded)
        if driver_then is None:
            return replace(unverifiable(other_numerics(recorded, here)), runtime_here=here)
        driver, here = driver_then, recorded
    result = run_race(track, rules, driver, racer=racer, seed=int(body["seed"]), keep_trace=False)
    claimed = body["laps"]
    outcome, detail = compare_laps(claimed, [lap.to_json() for lap in result.laps])
    return Verdict(race_id, racer, outcome, detail, here)


def cannot_rerun(race_id: str, racer: str, why: str, remedy: str = "") -> Verdict:
    """An unverifiable verdict: `why` (a phrase) it cannot be re-run here, and what would
    let it (`remedy`, a parenthesis)."""
    sentence = f"{why.rstrip('.')}, so it cannot be re-run here{remedy}"
    return Verdict(race_id, racer, "unverifiable", sentence)


def replay_setup(body: Mapping[str, Any]) -> tuple[Track, RaceRules] | str:
    """The track and rules to race a recorded race (or head-to-head race) again under, or
    why it cannot be raced here (a phrase)."""
    physics = body.get("physics") or BEFORE_VERSIONING
    if physics == PHYSICAL:
        return "its laps were timed by hand on a real track"
    if physics != CURRENT:
        return f"it was timed with {physics} and this racer-tui drives {CURRENT}"
    info = find_track_by_hash(str(body["track_hash"]))
    if info is None:
        return "its track is not on this machine"
    try:
        rules = rules_from_mapping(json.loads(body["rules"]))
    except RulesError as error:
        return f"its rules do not load here ({str(error).rstrip('.')})"
    return resolve_track(info.name), rules


def compare_laps(
    claimed: Sequence[dict[str, object]], driven: Sequence[dict[str, object]]
) -> tuple[Outcome, str]:
    for number, (said, did) in enumerate(zip(claimed, driven, strict=False), start=1):
        for field in ("raw_seconds", "time_seconds", "offtracks", "valid"):
            expected, actual = float(said[field]), float(did[field])  # type: ignore[arg-type]
            if abs(expected - actual) > _TOLERANCE_S:
                what = "off-tracks" if field == "offtracks" else field.replace("_", " ")
                return (
                    "differs",
                    f"re-run here, its lap {number} has {what} {actual:g}, not the "
                    f"{expected:g} it claims",
                )
        # Counted since schema 15, and left out when none: a lap recorded before says
        # nothing of them, so they are held to what the lap says when it says it.
        for field in ("crashes", "reversals"):
            if field in said and said[field] != did.get(field, 0):
                return (
                    "differs",
                    f"re-run here, its lap {number} has {did.get(field, 0)} {field}, not the "
                    f"{said[field]} it claims",
                )
    if len(claimed) != len(driven):
        return (
            "differs",
            f"re-run here, it drives {len(driven)} laps in the time, not the {len(claimed)} "
            "it claims",
        )
    return "same", ""


def _withdraw(league: League, verdict: Verdict, digest: str) -> None:
    row = league.query_one(
        "SELECT signer, signature FROM sync_seals WHERE kind = 'race' AND record_id = ? "
        "AND content_hash = ?",
        (verdict.race_id, digest),
    )
    body = record_body(league, "races", verdict.race_id)
    record = SyncRecord("race", verdict.race_id, digest, body)
    if row is not None:
        record = record.sealed(Seal(str(row[0]), str(row[1])))
    store = get_setting(league, STORE_SETTING) or ""
    reason = f"it is racer {verdict.racer}'s, but {verdict.detail}"
    incoming.withdraw(league, store, record, reason, final=True)

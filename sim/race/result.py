"""A race's result: every lap, the score under the race's rules, and what raced.

Results cross machines (league sync, JSON output), so `RaceResult.from_json` validates
everything and recomputes the score from the laps rather than trusting it. A result
satisfies `league.ranking.Rankable`, so standings are `league.ranking.rank(results)`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from typing import Any

from sim.deepracer.vocabulary import is_physics
from sim.foundation.ids import is_valid_id
from sim.foundation.plain_names import MAX_NAME_LENGTH, is_plain_name
from sim.foundation.remedies import RemedyError
from sim.physics.labels import BEFORE_VERSIONING, CURRENT
from sim.race.rules import (
    RaceRules,
    RulesError,
    Score,
    lap_counts,
    rules_from_mapping,
    score_laps,
)
from sim.race.trace import RaceTrace

RESULT_FORMAT = 1
MAX_LAPS = 10_000
MAX_RUNTIME_LENGTH = 100  # a policy runtime's name (sim.training.runtimes): about 40 now
_HASH = re.compile(r"[\w:.\-]{1,200}")


class ResultError(RemedyError):
    """A race result that cannot be trusted or read; the message names the field."""


@dataclass(frozen=True)
class LapRecord:
    """One completed lap. `time_seconds` includes penalties; `raw_seconds` does not."""

    number: int  # 1-based
    time_seconds: float
    raw_seconds: float
    penalty_seconds: float
    offtracks: int
    valid: bool  # counts under the rules' off-track limit
    started_at: float  # race clock when the lap started, seconds
    # Crashes into boxes or bot cars (object-avoidance and head-to-bot races): each cost
    # the rules' collision penalty, inside `penalty_seconds`.
    crashes: int = 0
    # Times the car was put back after driving the wrong way (simapp's "reversed"): held
    # for the off-track penalty, inside `penalty_seconds`, without making the lap invalid.
    reversals: int = 0

    @property
    def resets(self) -> int:
        """Times the car was put back on the track in this lap, whatever the reason: what
        simapp's metrics call `reset_count` (immobilized is switched off in a race)."""
        return self.offtracks + self.crashes + self.reversals

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "number": self.number,
            "time_seconds": self.time_seconds,
            "raw_seconds": self.raw_seconds,
            "penalty_seconds": self.penalty_seconds,
            "offtracks": self.offtracks,
            "valid": self.valid,
            "started_at": self.started_at,
        }
        # Left out when none: most laps keep the form they had before these were counted.
        if self.crashes:
            data["crashes"] = self.crashes
        if self.reversals:
            data["reversals"] = self.reversals
        return data

    @classmethod
    def from_json(cls, data: object, where: str) -> LapRecord:
        if not isinstance(data, Mapping):
            raise ResultError(f"{where} must be an object.")
        lap = cls(
            number=_whole(data, "number", where, 1),
            time_seconds=_seconds(data, "time_seconds", where),
            raw_seconds=_seconds(data, "raw_seconds", where),
            penalty_seconds=_seconds(data, "penalty_seconds", where),
            offtracks=_whole(data, "offtracks", where, 0),
            valid=_flag(data, "valid", where),
            started_at=_seconds(data, "started_at", where),
            crashes=_whole(data, "crashes", where, 0) if "crashes" in data else 0,
            reversals=_whole(data, "reversals", where, 0) if "reversals" in data else 0,
        )
        if abs(lap.raw_seconds + lap.penalty_seconds - lap.time_seconds) > 1e-3:
            raise ResultError(f"{where}.time_seconds is not raw_seconds plus penalty_seconds.")
        return lap


def completed_lap(
    rules: RaceRules,
    *,
    number: int,
    started_at: float,
    time_seconds: float,
    penalty_seconds: float,
    offtracks: int,
    crashes: int,
    reversals: int,
) -> LapRecord:
    """A lap the car has just completed, valid when it counts under `rules`."""
    lap = LapRecord(
        number=number,
        time_seconds=time_seconds,
        raw_seconds=time_seconds - penalty_seconds,
        penalty_seconds=penalty_seconds,
        offtracks=offtracks,
        valid=True,
        started_at=started_at,
        crashes=crashes,
        reversals=reversals,
    )
    return lap if lap_counts(lap, rules) else replace(lap, valid=False)


def now_iso() -> str:
    """The current UTC time, ISO-8601 with milliseconds: fixed width, so it sorts as text."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


@dataclass(frozen=True, eq=False)
class RaceResult:
    """One entrant's time trial. Compared by identity: two runs are two results."""

    result_id: str  # sim.foundation.ids.new_id()
    racer: str  # the person
    model_name: str  # the car ("reference" for the reference driver)
    model_hash: str  # the driver's content hash
    track_name: str
    track_hash: str
    rules: RaceRules
    seed: int
    laps: tuple[LapRecord, ...]
    scoring: Score
    total_offtracks: int  # including off-tracks in a lap the window cut
    started_at: str  # ISO-8601 UTC
    trace: RaceTrace | None = None
    physics: str = CURRENT  # the simulator's physics (sim.physics.labels): lap times of
    # different physics are never ranked together
    runtime: str = ""  # the policy runtime that drove it (sim.training.runtimes); "": none

    # --- league.ranking.Rankable ---------------------------------------------------------
    @property
    def score(self) -> float | None:
        return self.scoring.value

    @property
    def scoring_offtracks(self) -> int:
        return self.scoring.offtracks

    @property
    def valid_laps(self) -> int:
        return self.scoring.valid_laps

    @property
    def recorded_at(self) -> str:
        return self.started_at

    @property
    def record_id(self) -> str:
        return self.result_id

    # --- summaries -----------------------------------------------------------------------
    @property
    def best_lap(self) -> LapRecord | None:
        """The fastest lap that counts (fewer off-tracks, then the earlier lap, on a tie)."""
        counting = [lap for lap in self.laps if lap.valid]
        if not counting:
            return None
        return min(
            counting, key=lambda lap: (round(lap.time_seconds, 6), lap.offtracks, lap.number)
        )

    @property
    def completed_laps(self) -> int:
        return len(self.laps)

    def with_trace(self, trace: RaceTrace | None) -> RaceResult:
        return replace(self, trace=trace)

    def to_json(self) -> dict[str, Any]:
        """Everything but the trace (traces are sim-trace CSV files)."""
        best = self.best_lap
        return {
            "format": RESULT_FORMAT,
            "result_id": self.result_id,
            "racer": self.racer,
            "model_name": self.model_name,
            "model_hash": self.model_hash,
            "track_name": self.track_name,
            "track_hash": self.track_hash,
            "rules": self.rules.to_dict(),
            "seed": self.seed,
            "started_at": self.started_at,
            "laps": [lap.to_json() for lap in self.laps],
            "scoring": {
                "value": self.scoring.value,
                "lap_numbers": list(self.scoring.lap_numbers),
                "offtracks": self.scoring.offtracks,
                "valid_laps": self.scoring.valid_laps,
            },
            "best_lap_seconds": None if best is None else best.time_seconds,
            "total_offtracks": self.total_offtracks,
            "physics": self.physics,
            **({"runtime": self.runtime} if self.runtime else {}),
        }

    @classmethod
    def from_json(cls, data: object) -> RaceResult:
        """Read a result written by `to_json` (perhaps on another machine), validated.

        The score is recomputed from the laps and the rules; a stored score that disagrees
        means the record was altered or written by a different scoring, and is rejected.
        """
        if not isinstance(data, Mapping):
            raise ResultError("a race result must be a JSON object.")
        fmt = data.get("format", RESULT_FORMAT)
        if fmt != RESULT_FORMAT:
            raise ResultError(
                f"race result format {fmt!r} is not supported; update racer-tui to read it."
            )
        result_id = data.get("result_id")
        if not is_valid_id(result_id):
            raise ResultError("result_id must be a 26-character record id.")
        assert isinstance(result_id, str)
        rules_data = data.get("rules")
        if not isinstance(rules_data, Mapping):
            raise ResultError("rules must be an object of race rules.")
        try:
            rules = rules_from_mapping(rules_data)
        except RulesError as error:
            raise ResultError(f"rules: {error}") from None
        laps_data = data.get("laps")
        if not isinstance(laps_data, list) or len(laps_data) > MAX_LAPS:
            raise ResultError(f"laps must be a list of at most {MAX_LAPS} laps.")
        laps = tuple(LapRecord.from_json(lap, f"laps[{i}]") for i, lap in enumerate(laps_data))
        # Only counting laps are surely driven laps: a timekept heat also lists the laps its
        # car did not finish and those the timekeeper struck out.
        counting = sum(1 for lap in laps if lap.valid)
        if rules.lap_count is not None and counting > rules.lap_count:
            raise ResultError(
                f"a race of {rules.lap_count} laps cannot have {counting} counting laps."
            )
        for i, lap in enumerate(laps):
            limit = rules.max_offtracks_per_lap
            if lap.number != i + 1:
                raise ResultError(f"laps[{i}].number must be {i + 1}, not {lap.number}.")
            if lap.valid and limit is not None and lap.offtracks > limit:
                raise ResultError(
                    f"laps[{i}] is marked valid with {lap.offtracks} off-tracks; "
                    f"the rules allow {limit}."
                )
        total_offtracks = _whole(data, "total_offtracks", "result", 0)
        if total_offtracks < sum(lap.offtracks for lap in laps):
            raise ResultError("total_offtracks is less than the off-tracks of its laps.")
        scoring = score_laps(laps, rules)
        stored = data.get("scoring")
        if isinstance(stored, Mapping) and not _same_score(stored.get("value"), scoring.value):
            raise ResultError("scoring.value does not match the laps under the rules.")
        seed = data.get("seed")
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
            raise ResultError("seed must be a whole number from 0 to 2^63 - 1.")
        # Results written before physics was recorded ran on racer-tui's first physics.
        physics = data.get("physics", BEFORE_VERSIONING)
        if not is_physics(physics):
            raise ResultError("physics must be 'racer-tui/<version>' or 'deepracer'.")
        assert isinstance(physics, str)
        runtime = data.get("runtime", "")
        if not isinstance(runtime, str) or len(runtime) > MAX_RUNTIME_LENGTH:
            raise ResultError(f"runtime must be text of at most {MAX_RUNTIME_LENGTH} characters.")
        return cls(
            result_id=result_id,
            racer=_name(data, "racer"),
            model_name=_name(data, "model_name"),
            model_hash=_hash(data, "model_hash"),
            track_name=_name(data, "track_name"),
            track_hash=_hash(data, "track_hash"),
            rules=rules,
            seed=seed,
            laps=laps,
            scoring=scoring,
            total_offtracks=total_offtracks,
            started_at=_timestamp(data, "started_at"),
            trace=None,
            physics=physics,
            runtime=runtime,
        )


def _same_score(stored: object, computed: float | None) -> bool:
    if computed is None or stored is None:
        return stored is None and computed is None
    if isinstance(stored, bool) or not isinstance(stored, int | float):
        return False
    return abs(float(stored) - computed) <= 1e-3


def _name(data: Mapping[str, Any], key: str) -> str:
    value = data.get(key)
    if not is_plain_name(value):
        raise ResultError(
            f"{key} must be 1 to {MAX_NAME_LENGTH} printable characters, without line "
            "breaks, control or invisible characters."
        )
    assert isinstance(value, str)
    return value


def _hash(data: Mapping[str, Any], key: str) -> str:
    value = data.get(key)
    if not isinstance(value, str) or not _HASH.fullmatch(value):
        raise ResultError(f"{key} must be a content hash (letters, digits, ':', '.', '-').")
    return value


def _timestamp(data: Mapping[str, Any], key: str) -> str:
    value = data.get(key)
    if isinstance(value, str) and len(value) <= 40:
        try:
            parsed = datetime.fromisoformat(value)
        except ValueError:
            parsed = None
        if parsed is not None and parsed.utcoffset() is not None:
            return value
    raise ResultError(f"{key} must be an ISO-8601 time with a UTC offset, like {now_iso()}.")


def _seconds(data: Mapping[str, Any], key: str, where: str) -> float:
    value = data.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ResultError(f"{where}.{key} must be a number of seconds.")
    number = float(value)
    if not math.isfinite(number) or not 0.0 <= number <= 1e6:
        raise ResultError(f"{where}.{key} must be a finite, non-negative number of seconds.")
    return number


def _whole(data: Mapping[str, Any], key: str, where: str, low: int) -> int:
    value = data.get(key)
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= 10**9:
        raise ResultError(f"{where}.{key} must be a whole number of at least {low}.")
    return value


def _flag(data: Mapping[str, Any], key: str, where: str) -> bool:
    value = data.get(key)
    if not isinstance(value, bool):
        raise ResultError(f"{where}.{key} must be true or false.")
    return value

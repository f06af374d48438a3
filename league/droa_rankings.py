"""A board as DeepRacer on AWS ranks it: its timing methods, its stats, its field names.

DeepRacer on AWS (DRoA) ranks a leaderboard's submissions by one of three timing methods
(`ModelPerformanceMetricsHelper.ts` and `jobFinalizer.ts` in aws-solutions/deepracer-on-aws):
`AVG_LAP_TIME` (the best average of `minimumLaps` consecutive completed laps),
`BEST_LAP_TIME` (the fastest lap) and `TOTAL_TIME` (all the laps run), in whole
milliseconds, lower first; a submission is ranked only when its longest run of
consecutive completed laps reaches `minimumLaps`, and a score it cannot have is
86,000,000. Penalty seconds are already inside each lap's time (its simulator adds them).

`droa_stats` computes DRoA's `SubmissionStats` from a result's laps, exactly as DRoA does
from its metrics file; `leaderboard --format droa` writes a board's rankings with them, so
a league that mirrors a DRoA event publishes what DRoA would. racer-tui's own ranking of
the same laps under matching rules (the `droa` preset, `sim.race.rules`) gives the same
order and the same scores: the tests hold the two to each other.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from league.store import League
from sim.race.rules import DEFAULT_RULES, RaceRules, RankingMethod, rules_from_mapping

INVALID_MS = 86_000_000  # DRoA's "no valid score" (its comment says 24 hours)


class TimingMethod(StrEnum):
    AVG_LAP_TIME = "AVG_LAP_TIME"
    BEST_LAP_TIME = "BEST_LAP_TIME"
    TOTAL_TIME = "TOTAL_TIME"


TIMING_OF_RANKING = {
    RankingMethod.BEST_AVERAGE: TimingMethod.AVG_LAP_TIME,
    RankingMethod.BEST_LAP: TimingMethod.BEST_LAP_TIME,
    RankingMethod.TOTAL_TIME: TimingMethod.TOTAL_TIME,
}


@dataclass(frozen=True)
class DroaLap:
    """One lap as DRoA's metrics record it."""

    elapsed_ms: int  # penalties included
    completed: bool  # completion_percentage == 100
    offtracks: int
    crashes: int
    resets: int  # DeepRacer counts off-tracks, crashes, immobilised and reversed cars


def droa_stats(laps: Sequence[DroaLap], minimum_laps: int) -> dict[str, Any]:
    """DRoA's SubmissionStats of these laps, in its field names and units."""
    count = len(laps)
    times = [lap.elapsed_ms for lap in laps]
    best = min([*times, INVALID_MS])
    best_offtracks = next((lap.offtracks for lap in laps if lap.elapsed_ms == best), 0)
    average, average_offtracks = INVALID_MS, 0
    if 0 < minimum_laps <= count:
        for start in range(count - minimum_laps + 1):
            window = laps[start : start + minimum_laps]
            if not all(lap.completed for lap in window):
                continue
            value = math.floor(sum(lap.elapsed_ms for lap in window) / minimum_laps)
            if value < average:  # the earliest of equal windows stays
                average, average_offtracks = value, sum(lap.offtracks for lap in window)
    resets = sum(lap.resets for lap in laps)
    return {
        "avgLapTime": average,
        "avgResets": resets / count if count else 0,
        "bestLapTime": best,
        "collisionCount": sum(lap.crashes for lap in laps),
        "completedLapCount": _longest_completed_run(laps),
        "offTrackCount": sum(lap.offtracks for lap in laps),
        "resetCount": resets,
        "totalLapTime": sum(times),
        "bestLapOffTrackCount": best_offtracks,
        "avgLapOffTrackCount": average_offtracks,
    }


def ranking_score(stats: dict[str, Any], timing: TimingMethod, minimum_laps: int) -> int | None:
    """The score DRoA ranks by, or None where it would not rank the submission."""
    if stats["completedLapCount"] < minimum_laps or stats["completedLapCount"] == 0:
        return None
    value = {
        TimingMethod.AVG_LAP_TIME: stats["avgLapTime"],
        TimingMethod.BEST_LAP_TIME: stats["bestLapTime"],
        TimingMethod.TOTAL_TIME: stats["totalLapTime"],
    }[timing]
    return None if value == INVALID_MS else int(value)


def _longest_completed_run(laps: Sequence[DroaLap]) -> int:
    longest = run = 0
    for lap in laps:
        run = run + 1 if lap.completed else 0
        longest = max(longest, run)
    return longest


@dataclass(frozen=True)
class DroaEntry:
    """A racer's result to rank: who, with what, and its laps."""

    alias: str
    model_name: str
    laps: tuple[DroaLap, ...]


def droa_rankings(
    entries: Sequence[DroaEntry], timing: TimingMethod, minimum_laps: int
) -> list[dict[str, Any]]:
    """DRoA's rankings of these entries: only those it would rank, lowest score first,
    each with its rank (equal scores share one, as DRoA's own rank does)."""
    scored: list[tuple[int, int, DroaEntry, dict[str, Any]]] = []
    for order, entry in enumerate(entries):
        stats = droa_stats(entry.laps, minimum_laps)
        score = ranking_score(stats, timing, minimum_laps)
        if score is not None:
            scored.append((score, order, entry, stats))
    scored.sort(key=lambda item: (item[0], item[1]))
    rankings: list[dict[str, Any]] = []
    rank, previous = 0, None
    for place, (score, _, entry, stats) in enumerate(scored, start=1):
        if score != previous:  # equal scores share the first one's rank
            rank, previous = place, score
        rankings.append(
            {
                "rank": rank,
                "userProfile": {"alias": entry.alias},
                "modelName": entry.model_name,
                "rankingScore": score,
                "stats": stats,
            }
        )
    return rankings


def droa_rules_for(rules: RaceRules) -> tuple[TimingMethod, int]:
    """DRoA's timing method and minimumLaps for racer-tui rules: an average is of
    `ranking_laps` laps in a row (DRoA's minimumLaps); best lap and total time need
    `min_laps` in a row to be ranked."""
    timing = TIMING_OF_RANKING[rules.ranking]
    if timing is TimingMethod.AVG_LAP_TIME:
        return timing, rules.ranking_laps
    return timing, rules.min_laps


def droa_laps(league: League, record_id: str, kind: str) -> tuple[DroaLap, ...]:
    """A submission's or a race's laps as DRoA's metrics would hold them: its resets are
    simapp's reset_count, every count that put the car back."""
    if kind == "submission":
        rows = league.conn.execute(
            "SELECT time_seconds, completion, completed, offtracks, crashes, "
            "COALESCE(immobilized, 0) + COALESCE(reversals, 0) AS others "
            "FROM submission_laps WHERE submission_id = ? ORDER BY number",
            (record_id,),
        ).fetchall()
        return tuple(
            DroaLap(
                elapsed_ms=round(row["time_seconds"] * 1000),
                completed=bool(row["completed"]) and row["completion"] >= 100,
                offtracks=row["offtracks"],
                crashes=row["crashes"],
                resets=row["offtracks"] + row["crashes"] + row["others"],
            )
            for row in rows
        )
    race = league.conn.execute("SELECT rules FROM races WHERE id = ?", (record_id,)).fetchone()
    rules = rules_from_mapping(json.loads(race["rules"])) if race is not None else DEFAULT_RULES
    rows = league.conn.execute(
        "SELECT time_seconds, penalty_seconds, offtracks, crashes, reversals FROM race_laps "
        "WHERE race_id = ? ORDER BY number",
        (record_id,),
    ).fetchall()
    laps: list[DroaLap] = []
    for row in rows:
        reversals = row["reversals"] or 0
        crashes = row["crashes"] or _crashes_in_penalty(row, rules)
        laps.append(
            DroaLap(
                elapsed_ms=round(row["time_seconds"] * 1000),
                completed=True,  # a race keeps its completed laps
                offtracks=row["offtracks"],
                crashes=crashes,
                resets=row["offtracks"] + crashes + reversals,
            )
        )
    return tuple(laps)


def _crashes_in_penalty(row: Mapping[str, Any], rules: RaceRules) -> int:
    """A lap's crashes when its record does not count them: none since schema 15 (they
    are counted then, NULL meaning none), and in a lap recorded before, what its penalty
    seconds hold beyond its off-tracks' (a reversal then is taken for a crash: those
    records kept neither)."""
    if row["reversals"] is not None:
        return 0
    collisions_s: float = row["penalty_seconds"] - row["offtracks"] * rules.penalty_seconds
    if rules.collision_penalty_seconds <= 0 or collisions_s <= 1e-9:
        return 0
    return round(collisions_s / rules.collision_penalty_seconds)

"""The local leaderboard cache: one `entries` row per submission and per race.

Each row holds what a leaderboard shows (best lap, average, valid laps, off-tracks) and
the ranking score under every ranking method, with corrections (disqualified laps)
applied. Scores come from sim.race.rules.score_laps, the same function races use, and are
stored rounded to the millisecond exactly as league.ranking.ranking_key rounds them, so an
SQL `ORDER BY` on the cached columns agrees with `rank()` within one racer.

The `board` table keeps each racer's best entry per track, race type and physics under
every method, clustered by (method, track), so the leaderboard of a track is one range
scan. Laps of different physics (sim.physics.labels) or race types (league.race_types: a
time trial, object avoidance, head-to-bot) are never ranked together: each has its own
board.

Both are derived data: `refresh_entries` recomputes the rows a change touched (call it in
the same transaction as the change, e.g. after sync inserts pulled rows) and
`rebuild_entries` recomputes everything.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from itertools import groupby
from typing import Any

from league.assembler import CONSOLE, DRFC
from league.race_types import TIME_TRIAL, race_type_of
from league.store import League
from sim.physics.labels import BEFORE_VERSIONING, DEEPRACER
from sim.race.rules import (
    DEFAULT_RULES,
    RaceRules,
    RankingMethod,
    lap_counts,
    rules_from_mapping,
    score_laps,
)

# Submissions are DeepRacer evaluations: each trial is one lap, ranked by the league's
# default rules (best lap, at most 3 off-tracks per lap, 3 laps for average/total), on
# the board of the race type the model was set up for (its training_params.yaml).
SUBMISSION_RULES = DEFAULT_RULES


@dataclass(frozen=True)
class ScoredLap:
    """A lap as scoring sees it (sim.race.rules.TimedLap)."""

    number: int
    time_seconds: float
    offtracks: int
    valid: bool


@dataclass(frozen=True)
class EntrySource:
    """The shared facts of one submission or race that its cache row is computed from."""

    entry_id: str
    kind: str  # "submission" | "race"
    racer: str
    track_hash: str
    physics: str
    model_name: str
    night_id: str | None
    recorded_at: str
    rules: RaceRules
    laps: tuple[ScoredLap, ...]
    # league.race_types; None: the rules' (a submission's is its own, scored as the league's)
    race_type: str | None = None


ENTRY_COLUMNS = (
    "entry_id",
    "kind",
    "racer",
    "track_hash",
    "physics",
    "race_type",
    "model_name",
    "night_id",
    "recorded_at",
    "laps_driven",
    "valid_laps",
    "offtracks",
    "best_lap",
    "average_lap",
    "native_method",
    "score_best_lap",
    "offtracks_best_lap",
    "score_best_average",
    "offtracks_best_average",
    "score_total_time",
    "offtracks_total_time",
)
_INSERT = (
    f"INSERT OR REPLACE INTO entries ({', '.join(ENTRY_COLUMNS)}) "
    f"VALUES ({', '.join('?' for _ in ENTRY_COLUMNS)})"
)


def score_column(method: RankingMethod) -> tuple[str, str]:
    """The cache columns (score, scoring off-tracks) for a ranking method."""
    return f"score_{method.value}", f"offtracks_{method.value}"


def entry_key_sql(score: str, offtracks: str) -> str:
    """A text that sorts like league.ranking.ranking_key for entries of one racer: no score
    last, the score in whole milliseconds (cached scores are already rounded to them), fewer
    off-tracks, more valid laps, the earlier time, then the id (after a NUL, so a shorter
    time sorts first exactly as in a tuple comparison)."""
    return (
        f"printf('%d%012d%09d%09d', {score} IS NULL, coalesce(round({score} * 1000), 0), "
        f"{offtracks}, 999999999 - valid_laps) || recorded_at || char(0) || entry_id"
    )


def best_entries_sql(score: str, offtracks: str, where: str, group_by: str) -> str:
    """Each group's best entry from `entries` (SQLite takes a grouped query's bare columns
    from the row that `min()` chose)."""
    return f"""
        SELECT entry_id, kind, racer, model_name, track_hash, night_id, recorded_at,
               laps_driven, valid_laps, offtracks, best_lap, average_lap,
               {score} AS score, {offtracks} AS scoring_offtracks, physics, race_type,
               min({entry_key_sql(score, offtracks)}) AS pick
        FROM entries {where}
        GROUP BY {group_by}
    """


# What makes a board, and each racer's one row on it: a track, a race type, a physics.
BOARD_GROUPS = "track_hash, race_type, physics, racer"


def _board_insert(method: RankingMethod, where: str) -> str:
    score, offtracks = score_column(method)
    return f"""
        INSERT INTO board (
            method, track_hash, race_type, physics, unscored, score, scoring_offtracks,
            valid_laps, recorded_at, racer, entry_id, kind, model_name, night_id, best_lap,
            average_lap, offtracks, laps_driven
        )
        SELECT '{method.value}', track_hash, race_type, physics, score IS NULL,
               coalesce(score, 0), scoring_offtracks, valid_laps, recorded_at, racer, entry_id,
               kind, model_name, night_id, best_lap, average_lap, offtracks, laps_driven
        FROM ({best_entries_sql(score, offtracks, where, BOARD_GROUPS)})
    """


def _refresh_board(conn: sqlite3.Connection, ids: Sequence[str]) -> None:
    """Recompute the board rows of every (track, racer) these entries belong to."""
    pairs = conn.execute(
        "SELECT DISTINCT track_hash, racer FROM entries "
        "WHERE entry_id IN (SELECT value FROM json_each(?))",
        (json.dumps(list(ids)),),
    ).fetchall()
    for track_hash, racer in pairs:
        conn.execute(
            "DELETE FROM board WHERE method IN (SELECT value FROM json_each(?)) "
            "AND track_hash = ? AND racer = ?",
            (json.dumps([method.value for method in RankingMethod]), track_hash, racer),
        )
        for method in RankingMethod:
            conn.execute(
                _board_insert(method, "WHERE track_hash = ? AND racer = ?"), (track_hash, racer)
            )


def rebuild_board(conn: sqlite3.Connection) -> None:
    conn.execute("DELETE FROM board")
    for method in RankingMethod:
        conn.execute(_board_insert(method, ""))


def entry_values(source: EntrySource, disqualified: Iterable[int] = ()) -> tuple[Any, ...]:
    """The cache row for `source`, with the laps numbered in `disqualified` not counting."""
    removed = set(disqualified)
    laps = [
        replace(lap, valid=False) if lap.number in removed else lap
        for lap in sorted(source.laps, key=lambda lap: lap.number)
    ]
    counting = [lap.time_seconds for lap in laps if lap_counts(lap, source.rules)]
    scores: list[Any] = []
    for method in RankingMethod:
        score = score_laps(laps, replace(source.rules, ranking=method))
        scores += [None if score.value is None else round(score.value, 3), score.offtracks]
    return (
        source.entry_id,
        source.kind,
        source.racer,
        source.track_hash,
        source.physics,
        source.race_type or race_type_of(source.rules),
        source.model_name,
        source.night_id,
        source.recorded_at,
        len(laps),
        len(counting),
        sum(lap.offtracks for lap in laps),
        min(counting) if counting else None,
        sum(counting) / len(counting) if counting else None,
        source.rules.ranking.value,
        *scores,
    )


def store_entries(conn: sqlite3.Connection, rows: Iterable[tuple[Any, ...]]) -> None:
    conn.executemany(_INSERT, rows)


def _disqualified(conn: sqlite3.Connection, ids: Sequence[str] | None) -> dict[str, set[int]]:
    sql = "SELECT target, lap_number FROM corrections WHERE kind = 'disqualify_lap'"
    result: dict[str, set[int]] = {}
    wanted = None if ids is None else set(ids)
    for target, lap in conn.execute(sql):
        if wanted is None or target in wanted:
            result.setdefault(target, set()).add(int(lap))
    return result


def _rules(text: str, cache: dict[str, RaceRules]) -> RaceRules:
    if text not in cache:
        cache[text] = rules_from_mapping(json.loads(text))
    return cache[text]


def _in_clause(ids: Sequence[str] | None, column: str) -> tuple[str, list[str]]:
    if ids is None:
        return "", []
    return f"WHERE {column} IN (SELECT value FROM json_each(?))", [json.dumps(list(ids))]


def _ranked_at(alias: str, column: str) -> str:
    """The time a result ranks by in a tie: its own, or when this league first saw it if it
    arrived claiming to be older than results already here (league.sync.dates.Arrivals)."""
    return (
        f"coalesce((SELECT seen_at FROM sync_first_seen WHERE entry_id = {alias}.id), "
        f"{alias}.{column})"
    )


def _sources(conn: sqlite3.Connection, ids: Sequence[str] | None) -> Iterator[EntrySource]:
    reader = conn.cursor()
    reader.row_factory = sqlite3.Row  # read by column name
    where, params = _in_clause(ids, "s.id")
    submissions = reader.execute(
        f"SELECT s.id, s.racer, s.track_hash, s.model_name, "
        f"{_ranked_at('s', 'submitted_at')} AS recorded_at, "
        "l.number, l.time_seconds, l.offtracks, l.completed AS counts, "
        f"coalesce(s.physics, CASE WHEN s.source IN ('{DRFC}', '{CONSOLE}') "
        f"THEN '{DEEPRACER}' ELSE '{BEFORE_VERSIONING}' END) AS physics, s.race_type "
        f"FROM submissions s LEFT JOIN submission_laps l ON l.submission_id = s.id {where} "
        "ORDER BY s.id, l.number",
        params,
    )
    for entry_id, rows in groupby(submissions, key=lambda row: row["id"]):
        group = list(rows)
        first = group[0]
        yield EntrySource(
            entry_id=entry_id,
            kind="submission",
            racer=first["racer"],
            track_hash=first["track_hash"],
            physics=first["physics"],
            model_name=first["model_name"],
            night_id=None,
            recorded_at=first["recorded_at"],
            rules=SUBMISSION_RULES,
            laps=_scored_laps(group),
            race_type=first["race_type"] or TIME_TRIAL,
        )
    where, params = _in_clause(ids, "r.id")
    races = reader.execute(
        "SELECT r.id, r.racer, r.track_hash, r.model_name, r.night_id, "
        f"{_ranked_at('r', 'started_at')} AS recorded_at, r.rules, "
        "l.number, l.time_seconds, l.offtracks, l.valid AS counts, "
        f"coalesce(r.physics, '{BEFORE_VERSIONING}') AS physics FROM races r "
        f"LEFT JOIN race_laps l ON l.race_id = r.id {where} ORDER BY r.id, l.number",
        params,
    )
    rules_cache: dict[str, RaceRules] = {}
    for entry_id, rows in groupby(races, key=lambda row: row["id"]):
        group = list(rows)
        first = group[0]
        yield EntrySource(
            entry_id=entry_id,
            kind="race",
            racer=first["racer"],
            track_hash=first["track_hash"],
            physics=first["physics"],
            model_name=first["model_name"],
            night_id=first["night_id"],
            recorded_at=first["recorded_at"],
            rules=_rules(first["rules"], rules_cache),
            laps=_scored_laps(group),
        )


def _scored_laps(rows: Sequence[sqlite3.Row]) -> tuple[ScoredLap, ...]:
    """A result's laps from its joined rows (none when the result has no lap)."""
    return tuple(
        ScoredLap(row["number"], row["time_seconds"], row["offtracks"], bool(row["counts"]))
        for row in rows
        if row["number"] is not None
    )


def refresh_entries(conn: sqlite3.Connection, ids: Sequence[str]) -> None:
    """Recompute the cache rows of these submissions/races (unknown ids are ignored)."""
    if not ids:
        return
    disqualified = _disqualified(conn, ids)
    store_entries(
        conn,
        (
            entry_values(source, disqualified.get(source.entry_id, ()))
            for source in _sources(conn, ids)
        ),
    )
    _refresh_board(conn, ids)


def rebuild_entries(conn: sqlite3.Connection) -> None:
    """Recompute the whole cache from the shared rows."""
    conn.execute("DELETE FROM entries")
    disqualified = _disqualified(conn, None)
    store_entries(
        conn,
        (
            entry_values(source, disqualified.get(source.entry_id, ()))
            for source in _sources(conn, None)
        ),
    )
    rebuild_board(conn)


# --- what one entry is made of (the leaderboard's row detail) --------------------------------


@dataclass(frozen=True)
class EvaluationTrial:
    """One trial of a submission's evaluation file, as stored."""

    number: int
    time_seconds: float
    completion: float
    status: str
    offtracks: int
    completed: bool


@dataclass(frozen=True)
class SubmissionFiles:
    """A submission's five source files as the league stored them. JSON columns are parsed
    here; one that cannot be read is None, shown as "not in the files"."""

    action_space: dict[str, Any] | None
    sensors: list[Any] | None
    neural_network: str | None
    training_algorithm: str | None
    hyperparameters: dict[str, Any] | None
    training: dict[str, Any] | None
    evaluation_file: str
    trials: tuple[EvaluationTrial, ...]


@dataclass(frozen=True)
class RaceLap:
    number: int
    time_seconds: float
    penalty_seconds: float
    offtracks: int
    valid: bool


@dataclass(frozen=True)
class EntryBreakdown:
    """A submission's files, or a race's laps. `found` is False when the record is gone
    (a leaderboard read a moment ago can outlive it)."""

    kind: str  # "submission" | "race"
    found: bool
    submission: SubmissionFiles | None = None
    race_laps: tuple[RaceLap, ...] = ()
    has_trace: bool = False  # a race that can be replayed here


def _parsed(value: str | None, kind: type[dict[str, Any]] | type[list[Any]]) -> Any:
    if value is None:
        return None
    try:
        parsed = json.loads(value)
    except ValueError:
        return None
    return parsed if isinstance(parsed, kind) else None


def entry_breakdown(league: League, kind: str, record_id: str) -> EntryBreakdown:
    """What the submission or race `record_id` is made of (reads the database: call it in
    a worker)."""
    if kind != "submission":
        race = league.conn.execute("SELECT 1 FROM races WHERE id = ?", (record_id,)).fetchone()
        laps = league.conn.execute(
            "SELECT number, time_seconds, penalty_seconds, offtracks, valid FROM race_laps "
            "WHERE race_id = ? ORDER BY number",
            (record_id,),
        ).fetchall()
        traced = league.conn.execute(
            "SELECT 1 FROM race_traces WHERE race_id = ?", (record_id,)
        ).fetchone()
        return EntryBreakdown(
            kind="race",
            found=race is not None,
            race_laps=tuple(
                RaceLap(
                    lap["number"],
                    lap["time_seconds"],
                    lap["penalty_seconds"],
                    lap["offtracks"],
                    bool(lap["valid"]),
                )
                for lap in laps
            ),
            has_trace=traced is not None,
        )
    data = league.conn.execute("SELECT * FROM submissions WHERE id = ?", (record_id,)).fetchone()
    if data is None:
        return EntryBreakdown(kind="submission", found=False)
    trials = league.conn.execute(
        "SELECT number, time_seconds, completion, status, offtracks, completed "
        "FROM submission_laps WHERE submission_id = ? ORDER BY number",
        (record_id,),
    ).fetchall()
    files = SubmissionFiles(
        action_space=_parsed(data["action_space"], dict),
        sensors=_parsed(data["sensors"], list),
        neural_network=data["neural_network"],
        training_algorithm=data["training_algorithm"],
        hyperparameters=_parsed(data["hyperparameters"], dict),
        training=_parsed(data["training"], dict),
        evaluation_file=data["evaluation_file"],
        trials=tuple(
            EvaluationTrial(
                row["number"],
                row["time_seconds"],
                row["completion"],
                row["status"],
                row["offtracks"],
                bool(row["completed"]),
            )
            for row in trials
        ),
    )
    return EntryBreakdown(kind="submission", found=True, submission=files)

"""The leaderboard: each racer's best entry per track, ranked by league.ranking.rank.

Entries are submissions (evaluations) and races. The cached `entries` table (see
league.entries) holds every entry's score under every ranking method with corrections
applied, and `board` each racer's best entry per board and method. A board is a track
under one race type (league.race_types) and one physics (sim.physics.labels): a track's
leaderboard of one race type is one range of the `board_in_order` index, already in the
league's one total order but for the last tie-breaks, which `in_ranking_order` settles with
`rank()`. Filtered boards (a night, a season) pick each racer's best straight from
`entries` and rank them all; so do boards that rank only results verified by replay (a
night's `verification` rule, or the viewer's choice): the results such a board does not
rank are left out before each racer's best is picked.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from enum import StrEnum
from itertools import groupby
from operator import attrgetter
from typing import Any, Final

from league.entries import BOARD_GROUPS, best_entries_sql, score_column
from league.errors import LeagueError
from league.race_types import RACE_TYPES, board_name
from league.racers import display_names_overrides
from league.ranking import counts_under, rank
from league.rows import rows_as
from league.store import League
from league.tracks import track_names
from league.trust.standing import result_standings
from sim.race.rules import RankingMethod, Verification, rules_from_mapping

BY_CHOICES: dict[str, RankingMethod] = {
    "best": RankingMethod.BEST_LAP,
    "average": RankingMethod.BEST_AVERAGE,
    "total": RankingMethod.TOTAL_TIME,
}


@dataclass(slots=True)
class LeaderboardRow:
    """One racer's best entry on one track (satisfies league.ranking.Rankable).

    Not frozen: `rank` is filled in once the rows are ranked (copying thousands of rows
    to set one field would cost more than the query).
    """

    record_id: str
    kind: str  # "submission" or "race"
    racer: str  # the racer's name (the tie-break uses it: it never changes)
    display_name: str
    model: str
    track_hash: str
    track_name: str
    night_id: str | None
    score: float | None
    scoring_offtracks: int
    valid_laps: int
    recorded_at: str
    best_lap: float | None
    average_lap: float | None
    offtracks: int
    laps_driven: int
    physics: str  # which simulator timed the laps (sim.physics.labels): each its own board
    race_type: str  # league.race_types: "time_trial", "object_avoidance"...: each its own board
    rank: int = 0
    # Its standing here (league.trust.standing: replayed, verifiable, unverifiable), once
    # `mark_verification` has worked it out; "" until then.
    verification: str = ""
    # The policy runtime that drove a race (sim.training.runtimes), filled in with its
    # standing; "" for a submission, the reference driver, a physical car, or until then.
    runtime: str = ""


@dataclass(frozen=True)
class Filters:
    track_hash: str | None = None
    racer: str | None = None  # racer name
    night_ids: Sequence[str] | None = None  # None: every entry; a list: races of these nights
    race_type: str | None = None  # None: every race type's boards; else that one's
    # Only results of this standing or better (a night's own rule may ask for more).
    verification: Verification = Verification.ANY
    # The garage's model hashes: its models' races are verifiable (league.trust.standing).
    local_models: frozenset[str] = frozenset()


def _where(filters: Filters) -> tuple[str, list[Any]]:
    clauses: list[str] = []
    params: list[Any] = []
    if filters.track_hash is not None:
        clauses.append("track_hash = ?")
        params.append(filters.track_hash)
    if filters.racer is not None:
        clauses.append("racer = ?")
        params.append(filters.racer)
    if filters.night_ids is not None:
        clauses.append(f"night_id IN ({', '.join('?' for _ in filters.night_ids)})")
        params.extend(filters.night_ids)
    if filters.race_type is not None:
        clauses.append("race_type = ?")
        params.append(filters.race_type)
    return (f"WHERE {' AND '.join(clauses)}" if clauses else ""), params


NATIVE_SCORE = (
    "CASE native_method WHEN 'best_average' THEN score_best_average "
    "WHEN 'total_time' THEN score_total_time ELSE score_best_lap END"
)
NATIVE_OFFTRACKS = (
    "CASE native_method WHEN 'best_average' THEN offtracks_best_average "
    "WHEN 'total_time' THEN offtracks_total_time ELSE offtracks_best_lap END"
)
# LeaderboardRow's fields in order, from a table or subquery aliased `b` with the cached
# columns; display and track names are filled in afterwards from small lookups (joining
# them row by row costs more than the rest of the query). The track name's place holds ''
# (Python's one empty string), not a copy of the 64-character track hash per row: that
# copy cost about what the race type's column costs.
# LeaderboardRow's fields by name (league.rows); the shown name and the track's name are
# filled in from their own tables once the rows are read.
_ROW_COLUMNS = """
    b.entry_id AS record_id, b.kind, b.racer, b.racer AS display_name, b.model_name AS model,
    b.track_hash, '' AS track_name, b.night_id, {score} AS score, b.scoring_offtracks,
    b.valid_laps, b.recorded_at, b.best_lap, b.average_lap, b.offtracks, b.laps_driven,
    b.physics, b.race_type
"""


def leaderboard(
    league: League, filters: Filters, method: RankingMethod | None = RankingMethod.BEST_LAP
) -> list[LeaderboardRow]:
    """Ranked rows, board by board, `rank` numbered from 1 per board.

    A board is one track under one race type and one physics: laps among boxes or bot
    cars, timed by another version of the car, or by DeepRacer's own simulator, are ranked
    on a board of their own, whose track name says which (league.race_types.board_name).
    Boards in the order of their names.
    `method=None` scores each entry by its own rules' method (a night's races).
    """
    if method is not None and filters.night_ids is None and not filters.verification.requires:
        return _ranked_boards(_board_rows(league, filters, method))
    entries = grouped_rows(league, filters, method, group_by=BOARD_GROUPS)
    return rank_groups(entries, board_of, _board_order(entries), rank)


def _board_order(rows: Sequence[LeaderboardRow]) -> list[tuple[str, str, str]]:
    """The boards of `rows` in the order of their names."""
    boards = {board_of(row): row.track_name for row in rows}
    return sorted(boards, key=lambda key: (boards[key].casefold(), key))


_BOARD_KEY = attrgetter("track_hash", "race_type", "physics")  # board_of, at C speed


def _ranked_boards(rows: list[LeaderboardRow]) -> list[LeaderboardRow]:
    """`rank_groups` for rows as `board_sql` returns them, board after board: each run of
    one board is ranked by `in_ranking_order` and numbered, boards in the order of their
    names. Thousands of rows are split where the board changes, in C (groupby), rather
    than looked up row by row."""
    boards = [(key, list(run)) for key, run in groupby(rows, _BOARD_KEY)]
    if len({key for key, _ in boards}) != len(boards):  # a board in two runs: not in order
        return rank_groups(rows, board_of, _board_order(rows), rank)
    boards.sort(key=lambda board: (board[1][0].track_name.casefold(), board[0]))
    result: list[LeaderboardRow] = []
    for _, run in boards:
        ranked = in_ranking_order(run)
        for position, row in enumerate(ranked, start=1):
            row.rank = position
        result.extend(ranked)
    return result


def in_ranking_order(rows: Sequence[LeaderboardRow]) -> list[LeaderboardRow]:
    """`rank(rows)` for one board's rows as `board_sql` returns them, without sorting them
    again: the board's scores are rounded to the millisecond as `ranking_key` rounds them,
    so the SQL order is the ranking order up to the last tie-breaks (the racer's name
    case-folded, then the id), and only rows tied before those are sorted."""
    result: list[LeaderboardRow] = []
    run: list[LeaderboardRow] = []
    tied: tuple[Any, ...] | None = None
    for row in rows:
        key = (row.score, row.scoring_offtracks, row.valid_laps, row.recorded_at)
        if key != tied and run:
            result.extend(rank(run) if len(run) > 1 else run)
            run = []
        run.append(row)
        tied = key
    result.extend(rank(run) if len(run) > 1 else run)
    return result


def _board_rows(league: League, filters: Filters, method: RankingMethod) -> list[LeaderboardRow]:
    """From the `board` table: each racer's best, sorted in SQL nearly as rank() will (the
    order only has to be close: rank() decides, and sorts a nearly sorted list fast)."""
    return _rows(league, *board_sql(filters, method))


def board_sql(filters: Filters, method: RankingMethod) -> tuple[str, list[Any]]:
    """The board query: one range of the `board_in_order` index, read in its order."""
    clauses = ["b.method = ?"]
    params: list[Any] = [method.value]
    if filters.track_hash is not None:
        clauses.append("b.track_hash = ?")
        params.append(filters.track_hash)
    if filters.race_type is not None:
        if filters.track_hash is None:
            # Every track's board of one race type: the race type is a column of the index
            # after the track, so the tracks are named (every entry's track is in `tracks`,
            # a foreign key) to read one range per track, still in order, with no sort.
            clauses.append("b.track_hash IN (SELECT track_hash FROM tracks)")
        clauses.append("b.race_type = ?")
        params.append(filters.race_type)
    if filters.racer is not None:
        clauses.append("b.racer = ?")
        params.append(filters.racer)
    columns = _ROW_COLUMNS.format(score="CASE WHEN b.unscored THEN NULL ELSE b.score END")
    sql = f"""
        SELECT {columns} FROM board b
        WHERE {" AND ".join(clauses)}
        ORDER BY b.track_hash, b.race_type, b.physics, b.unscored, b.score, b.scoring_offtracks,
                 b.valid_laps DESC, b.recorded_at, b.racer, b.entry_id
    """
    return sql, params


def grouped_rows(
    league: League, filters: Filters, method: RankingMethod | None, *, group_by: str
) -> list[LeaderboardRow]:
    """Each group's best entry straight from `entries` (for filtered, smaller sets)."""
    score, offtracks = (NATIVE_SCORE, NATIVE_OFFTRACKS) if method is None else score_column(method)
    where, params = _where(filters)
    counted, counted_params = _verification_clause(league, filters)
    if counted:
        where = f"{where} AND {counted}" if where else f"WHERE {counted}"
        params += counted_params
    inner = best_entries_sql(score, offtracks, where, group_by)
    sql = f"SELECT {_ROW_COLUMNS.format(score='b.score')} FROM ({inner}) b"
    return _rows(league, sql, params)


_STRICTNESS = (Verification.ANY, Verification.VERIFIABLE, Verification.REPLAYED)


def _verification_clause(league: League, filters: Filters) -> tuple[str, list[Any]]:
    """A condition on `entries` that leaves out the results a board does not rank under
    its verification rule: each night's own (frozen in its rules) or the filter's, the
    stricter of the two; ("", []) when every result counts."""
    if filters.night_ids is None:
        if not filters.verification.requires:
            return "", []
        where, params = _where(filters)
        # Only races can be raced again: a submission never counts under such a rule.
        races = f"{where} AND kind = 'race'" if where else "WHERE kind = 'race'"
        ids = [row[0] for row in league.query(f"SELECT entry_id FROM entries {races}", params)]
        found = result_standings(league, ids, filters.local_models)
        allowed = [i for i in ids if counts_under(found[i].standing, filters.verification)]
        return "entry_id IN (SELECT value FROM json_each(?))", [json.dumps(allowed)]
    required: dict[str, Verification] = {}
    for night_id, rules in league.query(
        "SELECT id, rules FROM nights WHERE id IN (SELECT value FROM json_each(?))",
        (json.dumps(list(filters.night_ids)),),
    ):
        rule = rules_from_mapping(json.loads(rules)).verification
        level = max(rule, filters.verification, key=_STRICTNESS.index)
        if level.requires:
            required[night_id] = level
    if not required:
        return "", []
    rows = league.query(
        "SELECT entry_id, night_id FROM entries WHERE night_id IN (SELECT value FROM json_each(?))",
        (json.dumps(list(required)),),
    )
    found = result_standings(league, [row[0] for row in rows], filters.local_models)
    left_out = [
        entry_id
        for entry_id, night_id in rows
        if not counts_under(found[entry_id].standing, required[night_id])
    ]
    return "entry_id NOT IN (SELECT value FROM json_each(?))", [json.dumps(left_out)]


def mark_verification(
    league: League, rows: Sequence[LeaderboardRow], local_models: Collection[str] = ()
) -> None:
    """Fill in each row's standing here (`verification`) and the policy runtime that drove
    it (`runtime`), for the rows a board shows."""
    ids = [row.record_id for row in rows]
    found = result_standings(league, ids, local_models)
    runtimes = {
        str(race_id): str(runtime)
        for race_id, runtime in league.query(
            "SELECT id, runtime FROM races WHERE runtime IS NOT NULL "
            "AND id IN (SELECT value FROM json_each(?))",
            (json.dumps(ids),),
        )
    }
    for row in rows:
        row.verification = found[row.record_id].standing.value
        row.runtime = runtimes.get(row.record_id, "")


def board_runtimes(rows: Sequence[LeaderboardRow]) -> list[str]:
    """The policy runtimes the rows' races were driven under (`mark_verification` fills
    them in). More than one on a board compares policies computed with different numerics,
    which can decide a near tie between two actions differently: a board says so."""
    return sorted({row.runtime for row in rows if row.runtime})


def mixed_runtimes(rows: Sequence[LeaderboardRow]) -> str | None:
    """The sentence a board prints under itself when its races were driven under more than
    one policy runtime; None when under one or none."""
    runtimes = board_runtimes(rows)
    if len(runtimes) < 2:
        return None
    return (
        f"These races were driven under {len(runtimes)} policy runtimes "
        f"({'; '.join(runtimes)}): their policies computed with different numerics."
    )


def _rows(league: League, sql: str, params: Sequence[Any]) -> list[LeaderboardRow]:
    cursor = league.conn.cursor()
    cursor.row_factory = None  # plain tuples: thousands of rows, matched by name once
    rows = rows_as(LeaderboardRow, cursor.execute(sql, params))
    shown = display_names_overrides(league)
    tracks = track_names(league)
    named: dict[tuple[str, str, str], str] = {}  # a board's name, worked out once per board
    for row in rows:
        if shown:
            row.display_name = shown.get(row.racer, row.racer)
        board = (row.track_hash, row.race_type, row.physics)
        name = named.get(board)
        if name is None:
            track = tracks.get(row.track_hash) or row.track_hash[:12]
            name = named[board] = board_name(track, row.physics, row.race_type)
        row.track_name = name
    return rows


def board_of(row: LeaderboardRow) -> tuple[str, str, str]:
    """The board a row is ranked on: its track under its race type and its physics."""
    return row.track_hash, row.race_type, row.physics


def race_types_on(league: League, track_hash: str) -> list[str]:
    """The race types with entries on a track's boards, in the league's order
    (league.race_types.RACE_TYPES): one probe of the `board_in_order` index per race type."""
    sql = "SELECT 1 FROM board WHERE method = ? AND track_hash = ? AND race_type = ? LIMIT 1"
    method = RankingMethod.BEST_LAP.value
    return [
        kind
        for kind in RACE_TYPES
        if league.conn.execute(sql, (method, track_hash, kind)).fetchone() is not None
    ]


def several_boards(rows: Sequence[LeaderboardRow]) -> bool:
    """Whether rows come from more than one board (then each row names its board)."""
    return len({board_of(row) for row in rows}) > 1


def rank_groups(
    entries: Sequence[LeaderboardRow],
    group: Callable[[LeaderboardRow], Any],
    order: Sequence[Any],
    ranked: Callable[[Sequence[LeaderboardRow]], list[LeaderboardRow]] = rank,
) -> list[LeaderboardRow]:
    """Rank each group with league.ranking.rank (or `ranked`, which must order as it does)
    and number it from 1; groups in `order`."""
    groups: dict[Any, list[LeaderboardRow]] = {}
    for entry in entries:
        groups.setdefault(group(entry), []).append(entry)
    result: list[LeaderboardRow] = []
    for key in order:
        for position, entry in enumerate(ranked(groups.get(key, [])), start=1):
            entry.rank = position
            result.append(entry)
    return result


# --- columns, sorting and limits ------------------------------------------------------------


class Column(StrEnum):
    RANK = "rank"
    RACER = "racer"
    MODEL = "model"
    TRACK = "track"
    SCORE = "score"
    BEST = "best"
    AVERAGE = "average"
    LAPS = "laps"
    OFFTRACKS = "offtracks"
    SUBMITTED = "submitted"
    VERIFICATION = "verification"


# Most trusted first: replayed here, then verifiable, then unverifiable, then not worked out.
_STANDING_ORDER: Final = {"replayed": 0, "verifiable": 1, "unverifiable": 2}


def _missing_last(value: float | None) -> tuple[bool, float]:
    return (value is None, value if value is not None else 0.0)


SORT_KEYS: dict[Column, Callable[[LeaderboardRow], Any]] = {
    Column.RANK: lambda row: (row.track_name.casefold(), row.rank),
    Column.RACER: lambda row: (row.display_name.casefold(), row.racer.casefold()),
    Column.MODEL: lambda row: row.model.casefold(),
    Column.TRACK: lambda row: (row.track_name.casefold(), row.rank),
    Column.SCORE: lambda row: _missing_last(row.score),
    Column.BEST: lambda row: _missing_last(row.best_lap),
    Column.AVERAGE: lambda row: _missing_last(row.average_lap),
    Column.LAPS: lambda row: row.valid_laps,
    Column.OFFTRACKS: lambda row: row.offtracks,
    Column.SUBMITTED: lambda row: row.recorded_at,
    Column.VERIFICATION: lambda row: _STANDING_ORDER.get(row.verification, 3),
}


def sort_rows(
    rows: Sequence[LeaderboardRow], column: str, *, reverse: bool = False
) -> list[LeaderboardRow]:
    """Rows ordered by a display column (stable: ties keep rank order)."""
    try:
        key = SORT_KEYS[Column(column)]
    except ValueError:
        choices = ", ".join(c.value for c in Column)
        raise LeagueError(f"cannot sort by {column!r}; choose one of {choices}.") from None
    return sorted(rows, key=key, reverse=reverse)


def method_for(by: str) -> RankingMethod:
    try:
        return BY_CHOICES[by]
    except KeyError:
        raise LeagueError(f"--by must be one of {', '.join(BY_CHOICES)}, not {by!r}.") from None

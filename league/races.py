"""Race results from the race engine, stored with their laps, frozen rules and model hash.

A race row is shared (synced); its per-step trace is large and local, so it goes into the
local `race_traces` table as compressed numpy columns, never into the shared rows.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from league.entries import refresh_entries
from league.errors import LeagueError
from league.race_types import TIME_TRIAL, board_name
from league.racers import check_name, display_names_overrides, ensure_racer
from league.store import League, record_body
from league.tracks import ensure_track, track_names
from sim.coach.plausible import first_impossible_lap
from sim.foundation.ids import content_hash, is_valid_id
from sim.foundation.remedies import Fix
from sim.physics.labels import CURRENT, PHYSICAL
from sim.physics.objects.settings import RaceType
from sim.race.result import RaceResult
from sim.race.trace import RaceTrace
from sim.tracks.catalog import find_track_by_hash, resolve_track
from sim.tracks.track import Track, TrackError

TRACE_FORMAT = "npz-v1"
LAP_COLUMNS = (
    "number",
    "time_seconds",
    "raw_seconds",
    "penalty_seconds",
    "offtracks",
    "valid",
    "started_at",
    "crashes",
    "reversals",
)
# Counted since schema 15: NULL in the table and left out of a lap's record when none, so
# laps stored before keep their content hash (league.records).
OPTIONAL_LAP_COLUMNS = frozenset({"crashes", "reversals"})


def lap_rows(result: RaceResult) -> list[dict[str, Any]]:
    """Each lap as its record holds it: the optional counts only when there are some."""
    rows: list[dict[str, Any]] = []
    for lap in result.laps:
        row: dict[str, Any] = {
            "number": lap.number,
            "time_seconds": lap.time_seconds,
            "raw_seconds": lap.raw_seconds,
            "penalty_seconds": lap.penalty_seconds,
            "offtracks": lap.offtracks,
            "valid": int(lap.valid),
            "started_at": lap.started_at,
        }
        if lap.crashes:
            row["crashes"] = lap.crashes
        if lap.reversals:
            row["reversals"] = lap.reversals
        rows.append(row)
    return rows


def record_race(
    league: League,
    result: RaceResult,
    night_id: str | None = None,
    *,
    heat_id: str | None = None,
) -> str:
    """Store `result` (one transaction) and return its race id, which is its result_id.

    Recording the same result twice is a no-op; the same id with other content is an
    error. With `night_id`, the race must be on the night's track under its frozen rules.
    """
    if not is_valid_id(result.result_id):
        raise LeagueError(f"race result id {result.result_id!r} is not a valid record id.")
    if result.rules.race_type is RaceType.HEAD_TO_MODEL:
        raise LeagueError(
            "a car's laps from a head-to-head race are not a race of their own: its boards "
            "rank time trials, and a lap among rivals does not compare with them (record "
            "the whole head-to-head race: league.head_to_heads)."
        )
    check_possible_laps(result)  # before the transaction: a floor may take a second to work out
    laps = lap_rows(result)
    with league.transaction():
        racer = ensure_racer(league, result.racer)
        fields_ = {
            "racer": racer,
            "track_hash": result.track_hash,
            "model_name": result.model_name,
            "model_hash": result.model_hash,
            "night_id": night_id,
            "heat_id": heat_id,
            "rules": json.dumps(result.rules.to_dict(), sort_keys=True),
            "seed": result.seed,
            "started_at": result.started_at,
            "total_offtracks": result.total_offtracks,
            "physics": result.physics,
            # Only a policy's races have one; the others' records stay as they always were.
            **({"runtime": result.runtime} if result.runtime else {}),
        }
        existing = league.query_one(
            "SELECT content_hash FROM races WHERE id = ?", (result.result_id,)
        )
        if existing is not None:
            if existing["content_hash"] == content_hash(record_body(fields_, {"laps": laps})):
                return result.result_id
            problem = (  # the app corrects nothing: it says the problem alone
                f"race {result.result_id} is already recorded with different content; "
                "a recorded race never changes"
            )
            raise LeagueError(
                f"{problem} (use `racer-tui correct` for corrections).", problem=problem
            )
        if night_id is not None:
            _check_night(league, night_id, result)
        ensure_track(league, result.track_hash, result.track_name)
        league.insert_record("races", fields_, record_id=result.result_id, children={"laps": laps})
        league.conn.executemany(
            f"INSERT INTO race_laps (race_id, {', '.join(LAP_COLUMNS)}) "
            f"VALUES (?, {', '.join('?' for _ in LAP_COLUMNS)})",
            [(result.result_id, *(lap.get(c) for c in LAP_COLUMNS)) for lap in laps],
        )
        if result.trace is not None:
            league.conn.execute(
                "INSERT INTO race_traces (race_id, format, data) VALUES (?, ?, ?)",
                (result.result_id, TRACE_FORMAT, _trace_bytes(result.trace)),
            )
        refresh_entries(league.conn, [result.result_id])
    return result.result_id


def check_possible_laps(result: RaceResult) -> None:
    """LeagueError unless every lap of `result` is one a car could drive on its track: no
    quicker than the track's floor for its physics (`sim.coach.plausible`)."""
    driven = [
        (lap.number, lap.raw_seconds)  # as driven: penalties only ever add time
        for lap in result.laps
        # A physical car's lap that does not count may be one it never finished (its time
        # is when it was given up) or one the timekeeper struck out.
        if result.physics != PHYSICAL or lap.valid
    ]
    impossible = first_impossible_lap(result.track_hash, result.physics, driven)
    if impossible is not None:
        raise LeagueError(f"The race was not recorded: {impossible.sentence(result.track_name)}.")


def record_race_as(league: League, result: RaceResult, racer: str) -> str:
    """Record `result` as `racer`'s race (a checked racer name) and return its race id.

    A race run in the app is labelled with its model until someone claims it; the league
    entry belongs to the person. Recording it again under the same racer is a no-op; under
    another racer it is refused (a recorded race never changes hands).
    """
    return record_race(league, replace(result, racer=check_name(racer)))


def _check_night(league: League, night_id: str, result: RaceResult) -> None:
    night = league.query_one("SELECT * FROM nights WHERE id = ?", (night_id,))
    if night is None:
        raise LeagueError(f"there is no league night {night_id}; see `racer-tui night list`.")
    if league.query_one("SELECT 1 FROM night_closures WHERE night_id = ?", (night_id,)):
        raise LeagueError(f"league night {night['name']!r} is closed; its results are final.")
    if night["track_hash"] != result.track_hash:
        raise LeagueError(
            f"the race was on {result.track_name!r}, not on league night "
            f"{night['name']!r}'s track; race on the night's track."
        )
    if json.loads(night["rules"]) != result.rules.to_dict():
        raise LeagueError(
            f"the race's rules differ from league night {night['name']!r}'s frozen rules; "
            "race under the night's rules (changing rules needs a new night)."
        )


def _trace_bytes(trace: RaceTrace) -> bytes:
    buffer = io.BytesIO()
    arrays = {
        spec.name: getattr(trace, spec.name)
        for spec in fields(trace)
        if spec.name != "track_length"
    }
    np.savez_compressed(buffer, track_length=np.float64(trace.track_length), **arrays)
    return buffer.getvalue()


def race_trace(league: League, race_id: str) -> RaceTrace | None:
    """The stored trace of a race, or None when it was recorded without one."""
    row = league.query_one("SELECT format, data FROM race_traces WHERE race_id = ?", (race_id,))
    if row is None or row["format"] != TRACE_FORMAT:
        return None
    with np.load(io.BytesIO(row["data"]), allow_pickle=False) as data:
        values: dict[str, Any] = {name: data[name] for name in data.files}
    values["track_length"] = float(values["track_length"])
    return RaceTrace(**values)


def race_result(league: League, race_id: str) -> RaceResult:
    """A stored race as a RaceResult (validated like any record that crossed machines)."""
    row = league.query_one("SELECT * FROM races WHERE id = ?", (race_id,))
    if row is None:
        raise LeagueError(f"there is no race {race_id} in this league.")
    laps = [
        {column: lap[column] for column in LAP_COLUMNS if lap[column] is not None}
        for lap in league.query(
            "SELECT * FROM race_laps WHERE race_id = ? ORDER BY number", (race_id,)
        )
    ]
    for lap in laps:
        lap["valid"] = bool(lap["valid"])
    track = league.query_one("SELECT name FROM tracks WHERE track_hash = ?", (row["track_hash"],))
    result = RaceResult.from_json(
        {
            "result_id": row["id"],
            "racer": row["racer"],
            "model_name": row["model_name"],
            "model_hash": row["model_hash"],
            "track_name": track["name"] if track else row["track_hash"][:12],
            "track_hash": row["track_hash"],
            "rules": json.loads(row["rules"]),
            "seed": row["seed"],
            "started_at": row["started_at"],
            "laps": laps,
            "total_offtracks": row["total_offtracks"],
            # NULL: recorded before physics was, which RaceResult reads as physics 1.
            **({"physics": row["physics"]} if row["physics"] is not None else {}),
            **({"runtime": row["runtime"]} if row["runtime"] is not None else {}),
        }
    )
    return result.with_trace(race_trace(league, race_id))


def best_lap_race(
    league: League, track_hash: str, physics: str, race_type: str = TIME_TRIAL
) -> str | None:
    """The recorded race with the league's best lap on a track, among races of `physics`
    and `race_type` (a lap among boxes is no ghost for a time trial) that kept their trace
    (a ghost needs one); None when there is none."""
    row = league.query_one(
        "SELECT e.entry_id FROM entries e WHERE e.track_hash = ? AND e.physics = ? "
        "AND e.race_type = ? AND e.best_lap IS NOT NULL "
        "AND EXISTS (SELECT 1 FROM race_traces t WHERE t.race_id = e.entry_id) "
        "ORDER BY e.best_lap, e.entry_id LIMIT 1",
        (track_hash, physics, race_type),
    )
    return None if row is None else str(row[0])


# --- recorded races, newest first, and replaying one ----------------------------------------

MAX_RECENT_RACES = 1000


@dataclass(frozen=True)
class RecordedRace:
    """One recorded race as a list of races shows it (laps as the leaderboard counts them,
    corrections applied)."""

    race_id: str
    started_at: str
    track_hash: str
    track_name: str
    racer: str
    display_name: str
    model_name: str
    best_lap: float | None
    valid_laps: int
    laps_driven: int
    night_id: str | None
    night_name: str | None
    has_trace: bool
    race_type: str = TIME_TRIAL  # league.race_types, from the race's rules
    physics: str = CURRENT  # sim.physics.labels: a physical car's hand-timed laps too

    @property
    def track_label(self) -> str:
        """Its board's name: the track, then its race type when not a time trial and its
        physics when not today's ("reinvent_base (physical)")."""
        return board_name(self.track_name, self.physics, self.race_type)


def recent_races(
    league: League, limit: int = 100, track_hash: str | None = None
) -> list[RecordedRace]:
    """The newest recorded races first (optionally on one track), at most `limit`.

    Newest by start time (then id, a time-sortable ULID, for a stable order). The inner
    query walks the newest-first indexes of migration 4; only the chosen rows are joined to
    their cached laps, night and trace.
    """
    count = max(1, min(int(limit), MAX_RECENT_RACES))
    where = "WHERE track_hash = ?" if track_hash is not None else ""
    params: list[Any] = [track_hash] if track_hash is not None else []
    rows = league.query(
        "SELECT r.id, r.started_at, r.track_hash, r.racer, r.model_name, r.night_id, "
        "e.best_lap, e.valid_laps, e.laps_driven, e.race_type, e.physics, "
        "n.name AS night_name, "
        "EXISTS (SELECT 1 FROM race_traces t WHERE t.race_id = r.id) AS has_trace "
        "FROM (SELECT id, started_at, track_hash, racer, model_name, night_id FROM races "
        f"{where} ORDER BY started_at DESC, id DESC LIMIT ?) r "
        "LEFT JOIN entries e ON e.entry_id = r.id "
        "LEFT JOIN nights n ON n.id = r.night_id "
        "ORDER BY r.started_at DESC, r.id DESC",
        [*params, count],
    )
    shown = display_names_overrides(league)
    tracks = track_names(league)
    return [
        RecordedRace(
            race_id=row["id"],
            started_at=row["started_at"],
            track_hash=row["track_hash"],
            track_name=tracks.get(row["track_hash"]) or row["track_hash"][:12],
            racer=row["racer"],
            display_name=shown.get(row["racer"], row["racer"]),
            model_name=row["model_name"],
            best_lap=row["best_lap"],
            valid_laps=row["valid_laps"] or 0,
            laps_driven=row["laps_driven"] or 0,
            night_id=row["night_id"],
            night_name=row["night_name"],
            has_trace=bool(row["has_trace"]),
            race_type=row["race_type"] or TIME_TRIAL,
            physics=row["physics"] or CURRENT,
        )
        for row in rows
    ]


def find_local_track(track_hash: str, name: str) -> Track | None:
    """This machine's copy of a league track, found by content hash (the name first; a track
    imported under another name, or an official one, is found by its hash), or None."""
    try:
        track = resolve_track(name)
        if track.content_hash == track_hash:
            return track
    except TrackError:
        pass
    info = find_track_by_hash(track_hash)
    if info is None:
        return None
    try:
        return resolve_track(info.name)
    except TrackError:
        return None  # damaged since it was listed: the tracks section says what is wrong


@dataclass(frozen=True)
class RaceReplay:
    """What replaying a recorded race needs: the result with its trace, and its track."""

    result: RaceResult
    track: Track


def race_replay(league: League, race_id: str) -> RaceReplay:
    """A recorded race ready to replay, or LeagueError saying why it cannot be."""
    result = race_result(league, race_id)
    if result.trace is None or len(result.trace) == 0:
        raise LeagueError(
            f"{result.racer}'s race on {result.track_name} has no trace here (a race's trace "
            "stays on the machine that ran it), so it cannot be replayed."
        )
    track = find_local_track(result.track_hash, result.track_name)
    if track is None:
        problem = (
            f"{result.racer}'s race was on track {result.track_name!r}, which is not on this "
            "machine"
        )
        raise LeagueError(
            f"{problem}; import that track with `racer-tui tracks import FILE` to replay it.",
            problem=problem,
            fix=Fix.IMPORT_TRACK,
        )
    return RaceReplay(result, track)

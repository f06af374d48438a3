"""League benchmark: a big league in a temporary database, and the queries racers wait on.

    python -m benchmarks.league.board [--json] [--racers N] [--submissions N]
        [--laps-per-submission N]

Fills a fresh database (bulk inserts, one transaction) with racers, submissions with
their laps, and a season of closed league nights with races, then times the leaderboard
for one track, the season standings and one submit (assembling a model folder's files
and storing them) onto that same, busiest, track. Figures are printed, never judged: the
targets are in the issue, and the machine's load moves them.
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from league.assembler import LAP_COLUMNS as SUBMISSION_LAP_COLUMNS
from league.assembler import assemble
from league.entries import (
    SUBMISSION_RULES,
    EntrySource,
    ScoredLap,
    entry_values,
    rebuild_board,
    store_entries,
)
from league.leaderboard import Filters, leaderboard
from league.opening import open_league
from league.racers import default_colour
from league.races import LAP_COLUMNS as RACE_LAP_COLUMNS
from league.seasons import get_season, season_standings
from league.store import League, now_iso, record_body
from league.submissions import submit
from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import (
    HYPERPARAMETERS_PATH,
    MODEL_METADATA_PATH,
    TRAINING_METRICS_PATH,
    EvaluationTrial,
    ModelMetadata,
    TrainingEpisode,
    TrainingMetrics,
    TrainingParams,
    default_hyperparameters,
    evaluation_metrics_path,
    evaluation_stamp,
    write_evaluation_metrics,
    write_hyperparameters,
    write_model_metadata,
    write_training_metrics,
    write_training_params,
)
from sim.foundation.ids import content_hash, new_id
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.race.rules import DEFAULT_RULES
from sim.tracks.catalog import resolve_track

TARGETS_MS = {"leaderboard": 50.0, "standings": 100.0, "submit": 20.0}
BENCH_TRACK = "beginner-oval"


def _timed(action: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Median wall time and median CPU time of `action` in milliseconds, after a warm-up.

    CPU time is reported beside wall time because a shared machine's load stretches the
    wall time of the same work; the CPU time is what the query itself costs.
    """
    action()
    wall, cpu = [], []
    for _ in range(repeat):
        started, started_cpu = time.perf_counter(), time.process_time()
        action()
        wall.append((time.perf_counter() - started) * 1000.0)
        cpu.append((time.process_time() - started_cpu) * 1000.0)
    return statistics.median(wall), statistics.median(cpu)


def _insert(league: League, table: str, rows: Sequence[dict[str, Any]]) -> None:
    if not rows:
        return
    columns = list(rows[0])
    league.conn.executemany(
        f"INSERT INTO {table} ({', '.join(columns)}) VALUES ({', '.join('?' for _ in columns)})",
        [tuple(row[c] for c in columns) for row in rows],
    )


def _record(fields: dict[str, Any], children: dict[str, Any] | None = None) -> dict[str, Any]:
    return {
        "id": new_id(),
        **fields,
        "content_hash": content_hash(record_body(fields, children)),
    }


def _lap_times(rng: random.Random, count: int, base: float) -> Iterator[tuple[float, int, bool]]:
    for _ in range(count):
        offtracks = 0 if rng.random() < 0.8 else rng.randint(1, 5)
        completed = rng.random() < 0.9
        yield round(base + rng.uniform(-1.5, 3.0) + 3.0 * offtracks, 3), offtracks, completed


def fill(
    league: League,
    *,
    racers: int,
    submissions: int,
    laps_per_submission: int,
    tracks: int,
    nights: int,
    racers_per_night: int,
    seed: int = 7,
) -> dict[str, Any]:
    """Bulk-insert a synthetic league; returns what the timed queries need."""
    rng = random.Random(seed)
    created = now_iso()
    with league.transaction():
        names = [f"racer-{i:05d}" for i in range(racers)]
        _insert(
            league,
            "racers",
            [
                _record(
                    {
                        "name": name,
                        "display_name": name,
                        "colour": default_colour(name),
                        "created_at": created,
                    }
                )
                for name in names
            ],
        )
        # Track 0 is a real track, so the timed submit lands on the busiest leaderboard.
        busy = resolve_track(BENCH_TRACK)
        track_hashes = [busy.content_hash] + [
            content_hash(f"bench-track-{i}") for i in range(1, tracks)
        ]
        track_names = [busy.name] + [f"bench-{i}" for i in range(1, tracks)]
        _insert(
            league,
            "tracks",
            [
                _record({"track_hash": h, "name": name, "created_at": created})
                for h, name in zip(track_hashes, track_names, strict=True)
            ],
        )
        entries: list[tuple[Any, ...]] = []
        for chunk_start in range(0, submissions, 10_000):
            rows: list[dict[str, Any]] = []
            lap_values: list[tuple[Any, ...]] = []
            for _ in range(chunk_start, min(chunk_start + 10_000, submissions)):
                racer = rng.choice(names)
                track = rng.randrange(tracks)
                lap_rows: list[dict[str, Any]] = [
                    {
                        "number": n,
                        "time_seconds": t,
                        "completion": 100.0 if done else 42.0,
                        "status": "Lap complete" if done else "Off track",
                        "offtracks": off,
                        "crashes": 0,
                        "completed": int(done),
                    }
                    for n, (t, off, done) in enumerate(
                        _lap_times(rng, laps_per_submission, 12.0 + track), start=1
                    )
                ]
                fields: dict[str, Any] = {
                    "racer": racer,
                    "track_hash": track_hashes[track],
                    "model_name": f"model-{rng.randrange(5)}",
                    "model_hash": content_hash(rng.random()),
                    "source": "racer-tui",
                    "action_space": None,
                    "sensors": None,
                    "neural_network": None,
                    "training_algorithm": None,
                    "hyperparameters": None,
                    "training": None,
                    "evaluation_file": "evaluation-bench.json",
                    "fingerprint": content_hash(rng.random()),
                    "submitted_at": now_iso(),
                    "physics": CURRENT_PHYSICS,
                }
                row = _record(fields, {"laps": lap_rows})
                rows.append(row)
                lap_values.extend(
                    (row["id"], *(lap.get(c) for c in SUBMISSION_LAP_COLUMNS)) for lap in lap_rows
                )
                source = EntrySource(
                    row["id"],
                    "submission",
                    racer,
                    fields["track_hash"],
                    CURRENT_PHYSICS,
                    fields["model_name"],
                    None,
                    fields["submitted_at"],
                    SUBMISSION_RULES,
                    tuple(
                        ScoredLap(
                            lap["number"],
                            lap["time_seconds"],
                            lap["offtracks"],
                            bool(lap["completed"]),
                        )
                        for lap in lap_rows
                    ),
                )
                entries.append(entry_values(source))
            _insert(league, "submissions", rows)
            league.conn.executemany(
                f"INSERT INTO submission_laps (submission_id, {', '.join(SUBMISSION_LAP_COLUMNS)}) "
                f"VALUES (?, {', '.join('?' for _ in SUBMISSION_LAP_COLUMNS)})",
                lap_values,
            )
        season_points = json.dumps([25, 18, 15, 12, 10, 8, 6, 4, 2, 1])
        season = _record({"name": "bench season", "points": season_points, "created_at": created})
        _insert(league, "seasons", [season])
        rules = json.dumps(DEFAULT_RULES.to_dict(), sort_keys=True)
        race_rows: list[dict[str, Any]] = []
        race_laps: list[tuple[Any, ...]] = []
        for night_no in range(nights):
            track_hash = track_hashes[night_no % tracks]
            night = _record(
                {
                    "name": f"night {night_no + 1}",
                    "track_hash": track_hash,
                    "season_id": season["id"],
                    "rules": rules,
                    "created_at": created,
                }
            )
            _insert(league, "nights", [night])
            pool = names[: racers_per_night * 2]
            for racer in rng.sample(pool, min(racers_per_night, len(pool))):
                laps: list[dict[str, Any]] = [
                    {
                        "number": n,
                        "time_seconds": t,
                        "raw_seconds": t - 3.0 * off,
                        "penalty_seconds": 3.0 * off,
                        "offtracks": off,
                        "valid": int(off <= 3),
                        "started_at": 15.0 * (n - 1),
                    }
                    for n, (t, off, _) in enumerate(_lap_times(rng, 12, 12.0), start=1)
                ]
                race_fields: dict[str, Any] = {
                    "racer": racer,
                    "track_hash": track_hash,
                    "model_name": "model-0",
                    "model_hash": content_hash(racer),
                    "night_id": night["id"],
                    "heat_id": None,
                    "rules": rules,
                    "seed": night_no,
                    "started_at": now_iso(),
                    "total_offtracks": sum(lap["offtracks"] for lap in laps),
                    "physics": CURRENT_PHYSICS,
                }
                race = _record(race_fields, {"laps": laps})
                race_rows.append(race)
                race_laps.extend(
                    (race["id"], *(lap.get(c) for c in RACE_LAP_COLUMNS)) for lap in laps
                )
                entries.append(
                    entry_values(
                        EntrySource(
                            race["id"],
                            "race",
                            racer,
                            track_hash,
                            CURRENT_PHYSICS,
                            "model-0",
                            night["id"],
                            race_fields["started_at"],
                            DEFAULT_RULES,
                            tuple(
                                ScoredLap(
                                    lap["number"],
                                    lap["time_seconds"],
                                    lap["offtracks"],
                                    bool(lap["valid"]),
                                )
                                for lap in laps
                            ),
                        )
                    )
                )
            _insert(
                league,
                "night_closures",
                [_record({"night_id": night["id"], "closed_by": "bench", "created_at": created})],
            )
        _insert(league, "races", race_rows)
        league.conn.executemany(
            f"INSERT INTO race_laps (race_id, {', '.join(RACE_LAP_COLUMNS)}) "
            f"VALUES (?, {', '.join('?' for _ in RACE_LAP_COLUMNS)})",
            race_laps,
        )
        store_entries(league.conn, entries)
        rebuild_board(league.conn)
    league.conn.execute("ANALYZE")
    return {
        "track_hash": track_hashes[0],
        "season_id": season["id"],
        "race_laps": len(race_laps),
        "races": len(race_rows),
    }


def _model_folder(root: Path) -> Path:
    """A racer-tui model folder with all five files, as the garage writes them."""
    folder = root / "bench-model"
    folder.mkdir()
    write_model_metadata(
        folder / MODEL_METADATA_PATH,
        ModelMetadata(discrete_grid(), ("camera",)),
    )
    write_hyperparameters(folder / HYPERPARAMETERS_PATH, default_hyperparameters())
    write_training_params(folder / "training_params.yaml", TrainingParams(world_name=BENCH_TRACK))
    episodes = tuple(
        TrainingEpisode(
            10.0, 1000 * (i + 1), 1000 * i, 1000, i + 1, i + 1, "training", 50.0, "Off track"
        )
        for i in range(500)
    )
    write_training_metrics(folder / TRAINING_METRICS_PATH, TrainingMetrics(episodes))
    trials = [
        EvaluationTrial(
            100.0, 15_000 * (i + 1), 15_000 * i, 15_000 - 100 * i, "Lap complete", trial=i + 1
        )
        for i in range(3)
    ]
    write_evaluation_metrics(folder / evaluation_metrics_path(evaluation_stamp()), trials)
    return folder


def run(args: argparse.Namespace) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="league-bench-") as tmp:
        root = Path(tmp)
        db_path = root / "league.db"
        with open_league(db_path) as league:
            started = time.perf_counter()
            facts = fill(
                league,
                racers=args.racers,
                submissions=args.submissions,
                laps_per_submission=args.laps_per_submission,
                tracks=args.tracks,
                nights=args.nights,
                racers_per_night=args.racers_per_night,
            )
            fill_seconds = time.perf_counter() - started
            season = get_season(league, facts["season_id"])
            board_rows = len(leaderboard(league, Filters(track_hash=facts["track_hash"])))
            leaderboard_ms = _timed(
                lambda: leaderboard(league, Filters(track_hash=facts["track_hash"])), args.repeat
            )
            standings_ms = _timed(lambda: season_standings(league, season), args.repeat)
            folder = _model_folder(root)
            counter = iter(range(10**9))

            def one_submit() -> None:
                submit(league, assemble(str(folder), f"bench-submitter-{next(counter)}"))

            submit_ms = _timed(one_submit, args.repeat)
            submission = assemble(str(folder), "bench-store-only")
            store_counter = iter(range(10**9))

            def store_only() -> None:
                from dataclasses import replace

                submit(league, replace(submission, racer=f"bench-store-{next(store_counter)}"))

            store_ms = _timed(store_only, args.repeat)
            league.conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        size = db_path.stat().st_size
    return {
        "racers": args.racers,
        "submissions": args.submissions,
        "submission_laps": args.submissions * args.laps_per_submission,
        "tracks": args.tracks,
        "season_nights": args.nights,
        "races": facts["races"],
        "race_laps": facts["race_laps"],
        "fill_seconds": round(fill_seconds, 1),
        "leaderboard_rows": board_rows,
        "timings_ms": {
            "leaderboard": round(leaderboard_ms[0], 2),
            "standings": round(standings_ms[0], 2),
            "submit": round(submit_ms[0], 2),
            "submit_store_only": round(store_ms[0], 2),
        },
        "cpu_ms": {
            "leaderboard": round(leaderboard_ms[1], 2),
            "standings": round(standings_ms[1], 2),
            "submit": round(submit_ms[1], 2),
            "submit_store_only": round(store_ms[1], 2),
        },
        "targets_ms": TARGETS_MS,
        "db_bytes": size,
    }


def _line(label: str, report: dict[str, Any], key: str) -> str:
    target = TARGETS_MS.get(key)
    goal = "" if target is None else f"{target:.0f}"
    wall, cpu = report["timings_ms"][key], report["cpu_ms"][key]
    return f"{label:<30}{wall:>10.2f}{cpu:>10.2f}{goal:>11}"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.league.board", description=__doc__)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--racers", type=int, default=10_000)
    parser.add_argument("--submissions", type=int, default=100_000)
    parser.add_argument("--laps-per-submission", type=int, default=10)
    parser.add_argument("--tracks", type=int, default=10)
    parser.add_argument("--nights", type=int, default=20, help="closed nights in the season")
    parser.add_argument("--racers-per-night", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=15, help="timed runs per figure")
    args = parser.parse_args(argv)
    report = run(args)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    lines = [
        f"league: {report['racers']:,} racers, {report['submissions']:,} submissions with "
        f"{report['submission_laps']:,} laps on {report['tracks']} tracks, "
        f"{report['races']:,} races ({report['race_laps']:,} laps) in "
        f"{report['season_nights']} closed nights; filled in {report['fill_seconds']} s",
        "",
        f"{'query':<30}{'wall ms':>10}{'cpu ms':>10}{'target ms':>11}",
        _line("leaderboard, one track", report, "leaderboard")
        + f"   ({report['leaderboard_rows']:,} racers)",
        _line("season standings", report, "standings"),
        _line("submit (read files + store)", report, "submit"),
        _line("submit (store only)", report, "submit_store_only"),
        "",
        f"database file: {report['db_bytes'] / 1e6:.1f} MB",
    ]
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Storing assembled submissions: the submission row, its laps and its cache row, in one
transaction, so an interrupted submit leaves nothing behind.

A submission is refused when another racer registered its model first
(league.sync.models), so this module stands above sync and league.records; the columns
of a submission's laps, which league.records reads too, are league.assembler's.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from league.assembler import LAP_COLUMNS, Submission, assemble
from league.entries import refresh_entries
from league.errors import LeagueError
from league.race_types import TIME_TRIAL
from league.racers import check_name, ensure_racer
from league.store import League, now_iso
from league.sync.models import local_refusal
from league.tracks import ensure_track
from sim.coach.plausible import first_impossible_lap


@dataclass(frozen=True)
class Submitted:
    submission_id: str
    duplicate: bool  # the very same submission was already in the league


def _json(value: Any) -> str | None:
    return None if value is None else json.dumps(value, sort_keys=True)


def submit(league: League, submission: Submission) -> Submitted:
    """Add `submission` to the league; sending the same one again adds nothing. A lap no
    car could drive is refused (LeagueError), before anything is written."""
    check_possible_laps(submission)
    fingerprint = submission.fingerprint
    with league.transaction():
        racer = ensure_racer(league, submission.racer)  # the stored spelling of the name
        # Through the racer index: a racer has few submissions, so no index on fingerprints.
        existing = league.query_one(
            "SELECT id FROM submissions WHERE racer = ? AND fingerprint = ?", (racer, fingerprint)
        )
        if existing is not None:
            return Submitted(str(existing["id"]), duplicate=True)
        laps = [lap.record() for lap in submission.laps]
        borrowed = local_refusal(league, racer, submission.model_hash)
        if borrowed is not None:
            raise LeagueError(
                f"{submission.evaluation_file}: {borrowed}, so it cannot be submitted."
            )
        ensure_track(league, submission.track_hash, submission.track_name)
        submission_id = league.insert_record(
            "submissions",
            {
                "racer": racer,
                "track_hash": submission.track_hash,
                "model_name": submission.model_name,
                "model_hash": submission.model_hash,
                "source": submission.source,
                "action_space": _json(submission.action_space),
                "sensors": _json(submission.sensors),
                "neural_network": submission.neural_network,
                "training_algorithm": submission.training_algorithm,
                "hyperparameters": _json(submission.hyperparameters),
                "training": _json(submission.training),
                "evaluation_file": submission.evaluation_file,
                "fingerprint": fingerprint,
                "submitted_at": now_iso(),
                "physics": submission.physics,
                # Left out (NULL) for a time trial: such records keep the body, and so the
                # content hash, they always had (league.records.OPTIONAL_COLUMNS).
                **(
                    {}
                    if submission.race_type == TIME_TRIAL
                    else {"race_type": submission.race_type}
                ),
            },
            children={"laps": laps},
        )
        insert_laps(league, submission_id, laps)
        refresh_entries(league.conn, [submission_id])
    return Submitted(submission_id, duplicate=False)


def check_possible_laps(submission: Submission) -> None:
    """LeagueError unless every completed lap is one a car could drive on the track: no
    quicker than the track's floor for the physics that timed it (`sim.coach.plausible`)."""
    driven = [(lap.number, lap.time_seconds) for lap in submission.completed_laps]
    impossible = first_impossible_lap(submission.track_hash, submission.physics, driven)
    if impossible is not None:
        raise LeagueError(
            f"{submission.evaluation_file}: {impossible.sentence(submission.track_name)}, "
            "so it cannot be submitted."
        )


def insert_laps(league: League, submission_id: str, laps: list[dict[str, Any]]) -> None:
    league.conn.executemany(
        f"INSERT INTO submission_laps (submission_id, {', '.join(LAP_COLUMNS)}) "
        f"VALUES (?, {', '.join('?' for _ in LAP_COLUMNS)})",
        [(submission_id, *(lap.get(column) for column in LAP_COLUMNS)) for lap in laps],
    )


def submit_model(
    league: League,
    model: str,
    racer: str,
    *,
    track: str | None = None,
    evaluation: Path | None = None,
    model_name: str | None = None,
    allow_stale: bool = False,
) -> tuple[Submission, Submitted]:
    """What `racer-tui submit MODEL --racer NAME` does (the app's garage too): assemble the
    model folder's files (its latest evaluation unless one is named) and store them.

    LeagueError names a missing or malformed file, or an evaluation made before the model
    last trained (unless `allow_stale`: the racer confirmed); nothing is written then."""
    submission = assemble(model, racer, track=track, evaluation=evaluation)
    if submission.stale and not allow_stale:
        raise LeagueError(
            f"{submission.stale}; evaluate it again (`racer-tui evaluate {model}`), or "
            "submit this evaluation anyway with --stale-ok."
        )
    if model_name:
        submission = replace(submission, model_name=check_name(model_name, "model name"))
    return submission, submit(league, submission)

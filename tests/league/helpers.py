"""Builders for league tests: model folders in every layout, race results, a league."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import (
    HYPERPARAMETERS_PATH,
    MODEL_METADATA_PATH,
    TRAINING_METRICS_PATH,
    TRAINING_PARAMS,
    EvaluationTrial,
    ModelMetadata,
    TrainingEpisode,
    TrainingMetrics,
    TrainingParams,
    default_hyperparameters,
    evaluation_metrics_path,
    write_evaluation_metrics,
    write_hyperparameters,
    write_model_metadata,
    write_training_metrics,
    write_training_params,
)
from sim.foundation.ids import new_id
from sim.physics.labels import CURRENT
from sim.race.head_to_head import HeadToHeadResult
from sim.race.result import LapRecord, RaceResult
from sim.race.rules import DEFAULT_RULES, RaceRules, score_laps
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track

TRACK = "beginner-oval"
REWARD = "def reward_function(params):\n    return 1.0\n"


def trials(lap_seconds: Sequence[float], offtracks: Sequence[int] = ()) -> list[EvaluationTrial]:
    """Evaluation trials, one completed lap each, with optional off-track counts."""
    result = []
    start = 5_000
    for i, seconds in enumerate(lap_seconds):
        ms = round(seconds * 1000)
        result.append(
            EvaluationTrial(
                completion_percentage=100.0,
                metric_time=start + ms,
                start_time=start,
                elapsed_time_in_milliseconds=ms,
                episode_status="Lap complete",
                off_track_count=offtracks[i] if i < len(offtracks) else 0,
                trial=i + 1,
            )
        )
        start += ms + 100
    return result


def training_metrics(episodes: int = 20) -> TrainingMetrics:
    return TrainingMetrics(
        tuple(
            TrainingEpisode(
                5.0,
                3000 * (i + 1),
                3000 * i,
                3000,
                i + 1,
                i + 1,
                "training",
                min(100.0, 5.0 * i),
                "Off track",
            )
            for i in range(episodes)
        )
    )


def model_folder(
    root: Path,
    name: str = "my-model",
    *,
    laps: Sequence[float] = (12.5, 12.1, 12.9),
    track: str = TRACK,
    stamp: str = "20240501120000",
) -> Path:
    """A racer-tui model folder as the garage writes it (DRfC's layout, the trainer's state
    beside), written with our writers; its evaluation is EvaluationMetrics-<stamp>.json."""
    folder = root / name
    folder.mkdir(parents=True)
    write_model_metadata(folder / MODEL_METADATA_PATH, ModelMetadata(discrete_grid(), ("vector",)))
    write_hyperparameters(folder / HYPERPARAMETERS_PATH, default_hyperparameters())
    world = resolve_track(track)
    write_training_params(
        folder / TRAINING_PARAMS,
        TrainingParams(world_name=world.name, track_hash=world.content_hash),
    )
    write_training_metrics(folder / TRAINING_METRICS_PATH, training_metrics())
    # As today's racer-tui writes it: the laps were timed by today's physics.
    write_evaluation_metrics(folder / evaluation_metrics_path(stamp), trials(laps), CURRENT)
    (folder / "training-state.json").write_text('{"state": "finished", "elapsed_seconds": 60}')
    return folder


def race_result(
    racer: str,
    lap_times: Sequence[float],
    *,
    offtracks: Sequence[int] = (),
    track: Track | None = None,
    rules: RaceRules = DEFAULT_RULES,
    model: str = "car",
    started_at: str = "2024-05-01T19:00:00.000Z",
    seed: int = 1,
) -> RaceResult:
    """A race result as the engine would report it (laps back to back from t = 0)."""
    raced_on = track or resolve_track(TRACK)
    records = []
    clock = 0.0
    limit = rules.max_offtracks_per_lap
    for i, seconds in enumerate(lap_times):
        off = offtracks[i] if i < len(offtracks) else 0
        penalty = off * rules.penalty_seconds
        records.append(
            LapRecord(
                number=i + 1,
                time_seconds=seconds + penalty,
                raw_seconds=seconds,
                penalty_seconds=penalty,
                offtracks=off,
                valid=limit is None or off <= limit,
                started_at=clock,
            )
        )
        clock += seconds + penalty
    laps = tuple(records)
    return RaceResult(
        result_id=new_id(),
        racer=racer,
        model_name=model,
        model_hash=f"hash-{model}",
        track_name=raced_on.name,
        track_hash=raced_on.content_hash,
        rules=rules,
        seed=seed,
        laps=laps,
        scoring=score_laps(laps, rules),
        total_offtracks=sum(lap.offtracks for lap in laps),
        started_at=started_at,
    )


def head_to_head_in_order(
    race: HeadToHeadResult,
    *racers: str,
    models: Sequence[str] = (),
    started_at: str | None = None,
) -> HeadToHeadResult:
    """Another head-to-head race, which `racers` finished in this order: `race`'s first
    cars (a real race's, so their laps are ones a car can drive), renamed, and `models`
    their models' names if given. Only a replay would tell it from the race it came from."""
    cars = tuple(
        replace(
            car,
            position=position,
            result=replace(
                car.result,
                racer=racer,
                model_name=models[position - 1] if models else car.result.model_name,
            ),
        )
        for position, (car, racer) in enumerate(zip(race.cars, racers, strict=False), start=1)
    )
    return replace(
        race, race_id=new_id(), cars=cars, started_at=started_at or race.started_at, incidents=()
    )

"""How soon a fresh model learns to finish laps among DeepRacer's objects.

    python -m benchmarks.training.objects [--minutes 10] [--track reinvent_base] [--json]
                                         [--only boxes|bots] [--keep FOLDER]

Two fresh lidar models with the object_avoidance reward template train, each in its own
training child process on one core (side by side when the machine has two cores or more):
- "3 shuffled boxes": object avoidance, 3 boxes drawn again every episode (the issue's
  measure);
- "3 bots": head-to-bot, 3 bot cars at 1 m/s changing lanes.
The figures are when the training's own evaluations (standing laps among the model's
objects, as DeepRacer's training evaluates) first finished every trial, the most laps any
of them finished, and a final evaluation of 5 trials among the objects. Figures are
printed, never judged.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from benchmarks.training.runs import bench_home, print_result, train_model, train_side_by_side

TRIALS = 5


@dataclass
class Run:
    label: str
    model: str
    options: dict[str, Any]
    steps: int = 0
    training_seconds: float = 0.0
    # (seconds into training, laps, trials) of each of the training's own evaluations.
    evaluations: list[tuple[float, int, int]] = field(default_factory=list)
    final_laps: int = 0
    final_progress: float = 0.0
    ended: str = ""

    @property
    def all_laps_at(self) -> float | None:
        """Seconds of training before an evaluation first finished every trial."""
        return next((at for at, laps, trials in self.evaluations if laps == trials), None)


def _train(run: Run, minutes: float) -> Run:
    trained = train_model(run.model, minutes)
    run.steps, run.training_seconds, run.ended = trained.steps, trained.seconds, trained.ended
    run.evaluations = trained.evaluations
    return run


def _evaluate(run: Run) -> None:
    from sim.garage.folder import open_model
    from sim.training.evaluation import evaluate_model

    report = evaluate_model(open_model(run.model), trials=TRIALS)
    run.final_laps = sum(1 for trial in report.trials if trial.lap_time is not None)
    run.final_progress = sum(trial.progress for trial in report.trials) / len(report.trials)


def run(track_name: str, minutes: float, only: str | None = None) -> dict[str, Any]:
    from sim.garage.options import new_model

    runs = [
        Run(
            "3 shuffled boxes",
            "bench-boxes",
            {"race_type": "object-avoidance", "obstacles": 3, "randomize_obstacles": True},
        ),
        Run(
            "3 bots",
            "bench-bots",
            {"race_type": "head-to-bot", "bots": 3, "bot_speed": 1.0, "bot_lane_change": True},
        ),
    ]
    if only is not None:
        runs = [item for item in runs if item.model == f"bench-{only}"]
    for item in runs:
        new_model(
            item.model,
            track=track_name,
            sensors=["lidar"],
            reward="object_avoidance",
            minutes=minutes,
            **item.options,
        )
    side_by_side = train_side_by_side(runs, lambda r: _train(r, minutes))
    for item in runs:
        _evaluate(item)
    return {
        "track": track_name,
        "minutes": minutes,
        "side_by_side": side_by_side,
        "runs": [_row(item) for item in runs],
    }


def _row(item: Run) -> dict[str, Any]:
    best = max(item.evaluations, key=lambda e: (e[1], -e[0]), default=None)
    return {
        "label": item.label,
        "ended": item.ended,
        "training_s": round(item.training_seconds, 1),
        "steps": item.steps,
        "evaluations": len(item.evaluations),
        "all_laps_after_s": None if item.all_laps_at is None else round(item.all_laps_at, 1),
        "most_laps_in_training": None if best is None else f"{best[1]}/{best[2]}",
        "most_laps_after_s": None if best is None else round(best[0], 1),
        "final_laps": f"{item.final_laps}/{TRIALS}",
        "final_mean_progress_percent": round(item.final_progress, 1),
    }


def _print(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(
        title=f"{result['minutes']:g} minutes of training among objects on {result['track']}"
    )
    columns = ("objects", "steps", "every trial a lap after", "most laps in training",
               "final 5 trials", "final mean progress")  # fmt: skip
    for column in columns:
        table.add_column(column, justify="right")
    for row in result["runs"]:
        first = row["all_laps_after_s"]
        most = row["most_laps_in_training"] or "-"
        table.add_row(
            row["label"],
            f"{row['steps']:,}",
            "never" if first is None else f"{first / 60:.1f} min",
            most
            if row["most_laps_after_s"] is None
            else f"{most} at {row['most_laps_after_s'] / 60:.1f} min",
            row["final_laps"],
            f"{row['final_mean_progress_percent']:.1f} %",
        )
    Console().print(table)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.training.objects",
        description=(__doc__ or "").split("\n")[0],
    )
    parser.add_argument("--minutes", type=float, default=10.0, help="training per model")
    parser.add_argument("--track", default="reinvent_base")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--only", choices=("boxes", "bots"), help="train one of the two")
    parser.add_argument("--keep", help="keep the models in this data folder")
    args = parser.parse_args(argv)
    with bench_home(args.keep):
        result = run(args.track, args.minutes, args.only)
    print_result(result, args.json, _print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

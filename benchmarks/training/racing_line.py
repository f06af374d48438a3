"""How close to the limit a fresh model gets in a short training, with and without the line.

    python -m benchmarks.training.racing_line [--minutes 15] [--track reinvent_base] [--json]
                                            [--keep FOLDER]

Two fresh vector models train on the track, each in its own training child process on one
core (side by side when the machine has two cores or more, else one after the other):
- "default": `racer-tui model new` as it is (follow_center_line, the console's default
  grid of 10 actions);
- "racing line": `--actions-from-line --reward racing_line` (10 actions clustered from the
  limit lap's line, and the reward that pays for the line and its speed).
Each is then evaluated (5 trials, one standing lap each, as DeepRacer does). The figures
are the best lap its training's own evaluations saw and the final evaluation's best and
mean lap, each as a percentage over the track's flying limit lap (racer-tui's car, any
action) and over the flying limit within the model's own actions. Figures are printed,
never judged.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from benchmarks.training.runs import bench_home, print_result, train_side_by_side

TRIALS = 5


@dataclass
class Run:
    label: str
    model: str
    training_best_lap: float | None = None
    evaluation_best: float | None = None
    evaluation_mean: float | None = None
    laps: int = 0
    steps: int = 0
    training_seconds: float = 0.0
    own_flying_limit: float = 0.0
    ended: str = ""


def _train(run: Run, minutes: float) -> Run:
    from sim.training import events
    from sim.training.launcher import TrainingProcess

    process = TrainingProcess.start(run.model, minutes, [])
    for event in process.events():
        if isinstance(event, events.Update):
            run.steps, run.training_seconds = event.total_steps, event.elapsed
        elif isinstance(event, events.Evaluation) and event.best_lap is not None:
            best = run.training_best_lap
            run.training_best_lap = event.best_lap if best is None else min(best, event.best_lap)
        elif isinstance(event, events.Ended):
            run.ended = event.kind
    process.wait()
    return run


def _evaluate(run: Run) -> None:
    from sim.coach.limit_lap import limit_lap
    from sim.garage.folder import open_model
    from sim.training.evaluation import evaluate_model

    folder = open_model(run.model)
    run.own_flying_limit = limit_lap(
        folder.track(), space=folder.metadata().action_space
    ).flying_seconds
    report = evaluate_model(folder, trials=TRIALS)
    laps = [trial.lap_time for trial in report.trials if trial.lap_time is not None]
    run.laps = len(laps)
    if laps:
        run.evaluation_best, run.evaluation_mean = min(laps), sum(laps) / len(laps)


def run(track_name: str, minutes: float) -> dict[str, Any]:
    from sim.coach.limit_lap import limit_lap
    from sim.garage.options import new_model
    from sim.tracks.catalog import resolve_track

    track = resolve_track(track_name)
    new_model("bench-default", track=track_name, minutes=minutes)
    new_model(
        "bench-line",
        track=track_name,
        minutes=minutes,
        actions_from_line=10,
        reward="racing_line",
    )
    runs = [Run("default", "bench-default"), Run("racing line", "bench-line")]
    side_by_side = train_side_by_side(runs, lambda r: _train(r, minutes))
    for item in runs:
        _evaluate(item)
    flying = limit_lap(track).flying_seconds
    return {
        "track": track.name,
        "minutes": minutes,
        "side_by_side": side_by_side,
        "flying_limit_s": round(flying, 3),
        "runs": [_row(item, flying) for item in runs],
    }


def _over(lap: float | None, limit: float) -> float | None:
    return None if lap is None or limit <= 0 else round((lap / limit - 1.0) * 100.0, 1)


def _row(item: Run, flying: float) -> dict[str, Any]:
    return {
        "label": item.label,
        "ended": item.ended,
        "training_s": round(item.training_seconds, 1),
        "steps": item.steps,
        "training_best_lap_s": _rounded(item.training_best_lap),
        "evaluation_laps": f"{item.laps}/{TRIALS}",
        "evaluation_best_lap_s": _rounded(item.evaluation_best),
        "evaluation_mean_lap_s": _rounded(item.evaluation_mean),
        "best_over_flying_limit_percent": _over(_best(item), flying),
        "own_flying_limit_s": round(item.own_flying_limit, 3),
        "best_over_own_flying_limit_percent": _over(_best(item), item.own_flying_limit),
    }


def _best(item: Run) -> float | None:
    laps = [lap for lap in (item.training_best_lap, item.evaluation_best) if lap is not None]
    return min(laps) if laps else None


def _rounded(value: float | None) -> float | None:
    return None if value is None else round(value, 3)


def _print(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(
        title=f"{result['minutes']:g} minutes of training on {result['track']} "
        f"(flying limit lap {result['flying_limit_s']:.3f} s)"
    )
    columns = ("model", "steps", "best in training", "final 5 trials: best / mean",
               "best over the limit", "over its own limit")  # fmt: skip
    for column in columns:
        table.add_column(column, justify="right")

    def text(value: float | None, suffix: str) -> str:
        if value is None:
            return "-"
        return f"{value:.3f}{suffix}" if suffix == " s" else f"{value:+.1f}{suffix}"

    for row in result["runs"]:
        best, mean = (
            text(row["evaluation_best_lap_s"], " s"),
            text(row["evaluation_mean_lap_s"], " s"),
        )
        table.add_row(
            row["label"],
            f"{row['steps']:,}",
            text(row["training_best_lap_s"], " s"),
            f"{best} / {mean} ({row['evaluation_laps']})",
            text(row["best_over_flying_limit_percent"], " %"),
            text(row["best_over_own_flying_limit_percent"], " %")
            + f" of {row['own_flying_limit_s']:.3f} s",
        )
    Console().print(table)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.training.racing_line",
        description=(__doc__ or "").split("\n")[0],
    )
    parser.add_argument("--minutes", type=float, default=15.0, help="training per model")
    parser.add_argument("--track", default="reinvent_base")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--keep", help="keep the models in this data folder")
    args = parser.parse_args(argv)
    with bench_home(args.keep):
        result = run(args.track, args.minutes)
    print_result(result, args.json, _print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

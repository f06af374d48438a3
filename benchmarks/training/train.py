"""Training benchmark: how fast fresh default models learn to lap, and how fast they lap.

    python -m benchmarks.training.train [--json] [--sensor vector --sensor lidar] [--camera]
                              [--laps-minutes 2] [--lap-minutes 10] [--hp KEY=VALUE ...]

For each sensor a fresh default model (`racer-tui model new`: hairpin circuit,
follow-the-centre-line reward, the default action space) trains in the real training
child process until 5 of 5 evaluation trials complete a lap, or the budget runs out; the
figures are training time, wall-clock time (child start-up included) and env steps until
then, and training throughput (env steps per second, collection and learning together).

Lap quality: two vector models train for `--lap-minutes` each and their best evaluation
lap (mean of 5 trials that all completed) is compared with the reference driver's lap on
the same track and physics: the default model, and a model whose action space spans the
car's limits (continuous, 0.1-4 m/s, +-30 degrees) with a reward for speed along the
track (`SPEED_REWARD` below), since the default reward pays for staying centred, not for
going fast. Models live in a temporary garage; figures are printed, never judged.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

TRACK_LAP_TARGET = 1.25  # best lap within 25% of the reference lap
THROUGHPUT_TARGET = 5_000
LAPS_TARGET_MINUTES = {"vector": 2.0, "lidar": 2.0, "sector_lidar": 2.0, "camera": 30.0}

# Speed along the track, squared: a lap's return then grows with speed (slower laps collect
# fewer points per step over more steps), and leaving the road ends the points.
SPEED_REWARD = '''import math


def reward_function(params):
    """Speed along the track, squared; almost nothing with a wheel off the road."""
    if params["is_offtrack"] or not params["all_wheels_on_track"]:
        return 1e-3
    waypoints = params["waypoints"]
    behind, ahead = params["closest_waypoints"]
    dx = waypoints[ahead][0] - waypoints[behind][0]
    dy = waypoints[ahead][1] - waypoints[behind][1]
    track_direction = math.degrees(math.atan2(dy, dx))
    error = abs(params["heading"] - track_direction) % 360.0
    error = min(error, 360.0 - error)
    along = params["speed"] * math.cos(math.radians(error))
    return float(max(along, 0.0) ** 2 / 4.0 + 0.01)
'''


@dataclass
class RunFigures:
    """One training run of the benchmark, as measured from its event stream."""

    label: str
    sensor: str
    budget_minutes: float
    laps_seconds: float | None = None  # training time until 5/5 evaluation laps
    laps_wall_seconds: float | None = None  # wall-clock time from launching the child
    laps_steps: int | None = None
    training_seconds: float = 0.0
    total_steps: int = 0
    steps_per_second: float = 0.0  # after the first update (start-up excluded)
    best_lap: float | None = None  # best mean lap of a 5/5 evaluation
    best_single_lap: float | None = None
    evaluations: int = 0
    ended: str = ""
    message: str = ""
    # Largest progress made in one 1/15 s step by the final policy, in metres of centre line.
    # Above what 4 m/s can cover (0.27 m), the car crossed between two legs of the track.
    largest_step_gain_m: float | None = None


def largest_step_gain(name: str) -> float:
    """Evaluate model `name` once more and measure its largest one-step progress gain."""
    from sim.deepracer.files import read_sim_trace
    from sim.garage.folder import open_model
    from sim.training.evaluation import evaluate_model

    folder = open_model(name)
    report = evaluate_model(folder)
    assert report.metrics_file is not None
    stamp = report.metrics_file.stem.removeprefix("EvaluationMetrics-")
    rows = read_sim_trace(folder.evaluation_trace_file(stamp))
    gain = 0.0
    # Trials follow each other in the trace: compare each trial's own driven steps (a row
    # that left the road is followed by the car put back, which is no step at all).
    resets = {"off_track", "crashed", "reversed", "immobilized"}
    for before, after in itertools.pairwise(rows):
        if before.episode == after.episode and before.episode_status not in resets:
            gain = max(gain, (after.progress - before.progress) / 100.0 * after.track_len)
    return gain


def _run(
    name: str,
    sensor: str,
    label: str,
    budget_minutes: float,
    *,
    stop_at_laps: bool,
    measure_seconds: float = 0.0,
) -> RunFigures:
    """Train model `name` in the child process; with `stop_at_laps`, stop once 5/5
    evaluation laps came and throughput was measured for `measure_seconds`."""
    from sim.training import events
    from sim.training.launcher import TrainingProcess

    figures = RunFigures(label=label, sensor=sensor, budget_minutes=budget_minutes)
    launched = time.monotonic()
    process = TrainingProcess.start(name, budget_minutes, ["--evaluation-seconds", "0"])
    first: events.Update | None = None
    for event in process.events():
        if isinstance(event, events.Update):
            figures.total_steps = event.total_steps
            figures.training_seconds = event.elapsed
            if first is None:
                first = event
            elif event.elapsed > first.elapsed:
                figures.steps_per_second = (event.total_steps - first.total_steps) / (
                    event.elapsed - first.elapsed
                )
            measured = event.elapsed - first.elapsed >= measure_seconds
            if stop_at_laps and figures.laps_seconds is not None and measured:
                process.stop()
        elif isinstance(event, events.Evaluation):
            figures.evaluations += 1
            complete = event.laps == event.trials
            if complete and figures.laps_seconds is None:
                figures.laps_seconds = event.elapsed
                figures.laps_wall_seconds = time.monotonic() - launched
                figures.laps_steps = event.total_steps
            if complete and event.lap_times:
                mean = sum(event.lap_times) / len(event.lap_times)
                if figures.best_lap is None or mean < figures.best_lap:
                    figures.best_lap = mean
            if event.best_lap is not None and (
                figures.best_single_lap is None or event.best_lap < figures.best_single_lap
            ):
                figures.best_single_lap = event.best_lap
        elif isinstance(event, events.Ended):
            figures.ended, figures.message = event.kind, event.message
    process.wait()
    return figures


def _hyperparameters(assignments: Sequence[str]) -> dict[str, object]:
    values: dict[str, object] = {}
    for item in assignments:
        key, _, text = item.partition("=")
        try:
            values[key] = int(text) if text.isdigit() else float(text)
        except ValueError:
            values[key] = text
    return values


def run(
    sensors: Sequence[str],
    laps_minutes: float | None,
    lap_minutes: float,
    hyperparameters: dict[str, object],
    measure_seconds: float = 30.0,
) -> dict[str, Any]:
    from sim.deepracer.action_space import FULL_RANGE_CONTINUOUS
    from sim.garage.options import create_from_spec, default_model_spec
    from sim.physics.reference_driver import reference_lap
    from sim.tracks.catalog import resolve_track

    base = default_model_spec()
    hp = {**base.hyperparameters, **hyperparameters}
    base = replace(base, hyperparameters=hp)  # type: ignore[arg-type]
    track = resolve_track(base.track)
    reference = reference_lap(track).lap_time
    runs: list[RunFigures] = []
    for sensor in sensors:
        name = f"bench-{sensor}".replace("_", "-")
        metadata = replace(base.metadata, sensors=(sensor,))
        create_from_spec(name, replace(base, metadata=metadata))
        budget = laps_minutes or LAPS_TARGET_MINUTES.get(sensor, 2.0)
        runs.append(
            _run(name, sensor, "default model", budget, stop_at_laps=True,
                 measure_seconds=measure_seconds)
        )  # fmt: skip
    if lap_minutes > 0:
        create_from_spec("bench-laps-default", base)
        runs.append(
            _run("bench-laps-default", "vector", "lap quality: default", lap_minutes,
                 stop_at_laps=False)
        )  # fmt: skip
        runs[-1].largest_step_gain_m = largest_step_gain("bench-laps-default")
        full = replace(
            base,
            metadata=replace(base.metadata, action_space=FULL_RANGE_CONTINUOUS),
            reward_source=SPEED_REWARD,
        )
        create_from_spec("bench-laps-full-range", full)
        runs.append(
            _run("bench-laps-full-range", "vector", "lap quality: full range, speed reward",
                 lap_minutes, stop_at_laps=False)
        )  # fmt: skip
        runs[-1].largest_step_gain_m = largest_step_gain("bench-laps-full-range")
    return {
        "track": track.name,
        "reference_lap_s": round(reference, 3),
        "hyperparameters": hp,
        "action_space": base.metadata.action_space.to_metadata(),
        "runs": [_row(r, reference) for r in runs],
    }


def _row(figures: RunFigures, reference: float) -> dict[str, Any]:
    row = asdict(figures)
    for key, value in row.items():
        if isinstance(value, float):
            row[key] = round(value, 3)
    best = figures.best_lap
    row["best_lap_vs_reference"] = None if best is None else round(best / reference, 3)
    row["laps_target_minutes"] = LAPS_TARGET_MINUTES.get(figures.sensor, 2.0)
    return row


def _print_tables(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    def show(value: Any, fmt: str = "") -> str:
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "-"
        return format(value, fmt)

    table = Table(
        title=f"Training benchmark on {result['track']} "
        f"(reference lap {result['reference_lap_s']:.3f} s)"
    )
    columns = ("run", "sensor", "budget", "to 5/5 laps", "wall", "steps", "steps/s",
               "best lap", "vs ref", "step gain")  # fmt: skip
    for column in columns:
        table.add_column(column, justify="right")
    for row in result["runs"]:
        table.add_row(
            row["label"],
            row["sensor"],
            f"{row['budget_minutes']:g} min",
            show(row["laps_seconds"], ".1f") + " s",
            show(row["laps_wall_seconds"], ".1f") + " s",
            show(row["laps_steps"], ","),
            show(row["steps_per_second"], ",.0f"),
            show(row["best_lap"], ".3f") + " s",
            show(row["best_lap_vs_reference"], ".2f"),
            show(row["largest_step_gain_m"], ".2f") + " m",
        )
    console = Console()
    console.print(table)
    console.print(f"hyperparameters: {json.dumps(result['hyperparameters'])}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.training.train", description=(__doc__ or "").split("\n")[0]
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--sensor", action="append", help="sensors to time to 5/5 laps (default: vector, lidar)"
    )
    parser.add_argument("--camera", action="store_true", help="also the camera (long)")
    parser.add_argument(
        "--laps-minutes", type=float, help="budget per sensor (default: the issue's target)"
    )
    parser.add_argument(
        "--lap-minutes", type=float, default=10.0, help="lap-quality budget (0: skip)"
    )
    parser.add_argument("--hp", action="append", default=[], help="hyperparameter KEY=VALUE")
    parser.add_argument(
        "--measure-seconds", type=float, default=30.0, help="throughput measuring time"
    )
    parser.add_argument("--keep", help="keep the models in this garage folder")
    args = parser.parse_args(argv)
    sensors = list(args.sensor or ["vector", "lidar"]) + (["camera"] if args.camera else [])
    with tempfile.TemporaryDirectory(prefix="racer-bench-") as scratch:
        os.environ["RACER_TUI_HOME"] = args.keep or scratch
        result = run(
            sensors,
            args.laps_minutes,
            args.lap_minutes,
            _hyperparameters(args.hp),
            args.measure_seconds,
        )
    if args.json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
    else:
        _print_tables(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

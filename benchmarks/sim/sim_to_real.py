"""Sim-to-real proxy: does camera randomisation keep a policy driving on pictures it never
trained on?

    python -m benchmarks.sim.sim_to_real [--minutes 20] [--trials 10] [--track reinvent_base]
                                    [--json] [--keep FOLDER]

Two fresh camera models (FRONT_FACING_CAMERA, `racer-tui model new`'s defaults otherwise)
train for the same time on the track, each in its own training child process on one core
(side by side when the machine has two cores or more): one on the plain render, one with
camera randomisation at its default strengths (`sim.sensors.randomisation`). Each is then evaluated,
`--trials` one-lap trials from the start line ending at the first off-track (as training's
own evaluations), on the plain render and on pictures outside what either saw in training:

- darker: the light's gain at 0.45 (randomisation draws 0.67-1.5);
- noisier: sensor noise of 12 grey levels (it draws 0-6);
- pitch +5 deg: the camera tilted 5 degrees further down (it draws +-3);
- line colours: edge bands grey 150 and centre dashes 230 (it draws 171-251 and 100-180).

The figures, side by side: lap completion (the share of trials that finished a lap), mean
progress and the mean lap time of the trials that finished. Printed, never judged.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from benchmarks.training.runs import bench_home, print_result, train_model, train_side_by_side
from sim.sensors.randomisation.perturbation import PLAIN, CameraPerturbation, Palette

DEFAULT_MINUTES = 20.0
DEFAULT_TRIALS = 10
TRIAL_SECONDS = 60.0  # a trial still running after this is "Time Up"
# Pictures neither model trained on (the randomised model's default ranges are in
# sim.sensors.randomisation.perturbation; every one of these lies outside them).
CONDITIONS: dict[str, CameraPerturbation] = {
    "plain": PLAIN,
    "darker": CameraPerturbation(gain=0.45),
    "noisier": CameraPerturbation(noise=12.0),
    "pitch +5 deg": CameraPerturbation(pitch_deg=5.0),  # further down
    "line colours": CameraPerturbation(palette=Palette(border=150, centre=230)),
}


@dataclass
class Run:
    label: str
    model: str
    randomised: bool
    steps: int = 0
    training_seconds: float = 0.0
    ended: str = ""
    # condition -> (trials with a lap, trials, mean progress %, mean lap time or None)
    results: dict[str, tuple[int, int, float, float | None]] = field(default_factory=dict)


def _train(run: Run, minutes: float) -> Run:
    trained = train_model(run.model, minutes)
    run.steps, run.training_seconds, run.ended = trained.steps, trained.seconds, trained.ended
    return run


def _evaluate(run: Run, trials: int) -> None:
    from benchmarks.sim.perturbed_driver import perturbed_driver
    from sim.garage.folder import open_model
    from sim.training.evaluation import run_trials

    folder = open_model(run.model)
    if not folder.has_policy():
        return
    track = folder.track()
    for name, perturbation in CONDITIONS.items():
        driver = perturbed_driver(folder, perturbation)
        results = run_trials(driver, track, trials, max_seconds=TRIAL_SECONDS)
        laps = [r.lap_time for r in results if r.lap_time is not None]
        progress = sum(r.progress for r in results) / len(results)
        mean_lap = sum(laps) / len(laps) if laps else None
        run.results[name] = (len(laps), len(results), progress, mean_lap)


def run(track_name: str, minutes: float, trials: int) -> dict[str, Any]:
    from sim.garage.folder import MIN_MINUTES
    from sim.garage.options import new_model
    from sim.sensors.randomisation.settings import CameraRandomisation

    runs = [
        Run("plain", "sim-to-real-plain", randomised=False),
        Run("randomised", "sim-to-real-randomised", randomised=True),
    ]
    for item in runs:
        new_model(
            item.model,
            track=track_name,
            sensors=["FRONT_FACING_CAMERA"],
            minutes=max(minutes, MIN_MINUTES),
            camera_randomisation=CameraRandomisation()
            if item.randomised
            else CameraRandomisation.OFF,
        )
    side_by_side = train_side_by_side(runs, lambda r: _train(r, minutes))
    for item in runs:
        _evaluate(item, trials)
    return {
        "track": track_name,
        "minutes": minutes,
        "trials": trials,
        "side_by_side": side_by_side,
        "randomisation": CameraRandomisation().describe(),
        "conditions": list(CONDITIONS),
        "runs": [_row(item) for item in runs],
    }


def _row(item: Run) -> dict[str, Any]:
    return {
        "label": item.label,
        "ended": item.ended,
        "training_s": round(item.training_seconds, 1),
        "steps": item.steps,
        "conditions": {
            name: {
                "laps": laps,
                "trials": trials,
                "lap_completion_percent": round(100.0 * laps / trials, 1),
                "mean_progress_percent": round(progress, 1),
                "mean_lap_s": None if lap is None else round(lap, 3),
            }
            for name, (laps, trials, progress, lap) in item.results.items()
        },
    }


def _print(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    console.width = max(console.width, 100)  # the two models' figures side by side
    runs = result["runs"]
    table = Table(
        title=(
            f"{result['minutes']:g} minutes of training on {result['track']}, "
            f"{result['trials']} trials per picture"
        )
    )
    table.add_column("picture")
    for row in runs:
        for what in ("laps", "progress", "lap time"):
            table.add_column(f"{row['label']}\n{what}", justify="right")
    for name in result["conditions"]:
        cells = [name]
        for row in runs:
            seen = row["conditions"].get(name)
            if seen is None:
                cells += ["-", "-", "-"]
                continue
            lap = seen["mean_lap_s"]
            cells += [
                f"{seen['lap_completion_percent']:.0f}% {seen['laps']}/{seen['trials']}",
                f"{seen['mean_progress_percent']:.1f}%",
                "-" if lap is None else f"{lap:.2f} s",
            ]
        table.add_row(*cells)
    console.print(table)
    for row in runs:
        seconds = row["training_s"]
        rate = f", {row['steps'] / seconds:,.0f} steps/s" if seconds > 0 else ""
        console.print(
            f"{row['label']}: {row['steps']:,} steps in {seconds:.0f} s of training{rate} "
            f"({row['ended'] or 'no end reported'})"
        )
    console.print(f"the randomised model's camera randomisation: {result['randomisation']}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sim.sim_to_real",
        description=(__doc__ or "").split("\n")[0],
    )
    parser.add_argument("--minutes", type=float, default=DEFAULT_MINUTES, help="training per model")
    parser.add_argument("--trials", type=int, default=DEFAULT_TRIALS, help="per picture")
    parser.add_argument("--track", default="reinvent_base")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--keep", help="keep the models in this data folder")
    args = parser.parse_args(argv)
    if not args.minutes > 0:
        parser.error("--minutes must be more than 0")
    if not 1 <= args.trials <= 100:
        parser.error("--trials must be from 1 to 100")
    with bench_home(args.keep):
        result = run(args.track, args.minutes, args.trials)
    print_result(result, args.json, _print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

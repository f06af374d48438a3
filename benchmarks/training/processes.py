"""Training across cores: env steps per second of one training on 1 process and on N.

    python -m benchmarks.training.processes [--seconds 60] [--processes 2]
                                           [--sensor vector --sensor lidar --sensor camera]
                                           [--json] [--keep DIR]

For each sensor a fresh default model (`racer-tui model new --sensor S`) trains for
`--seconds` in the real training child, once with `--processes 1` and once with
`--processes N` (one after the other, never side by side: each run is to have the machine),
and the figure is its steps per second over the run (collection and learning together,
from its last update). With N processes the fleet is N times the cars and the PPO update
runs N threads (sim.training.shards). The last of the run's own evaluations is printed
beside, so a faster run that learns nothing would show. Figures are printed, never judged.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from benchmarks.training.runs import Trained, bench_home, print_result, train_model

SENSORS = ("vector", "lidar", "camera")


def run(sensors: Sequence[str], seconds: float, processes: int) -> dict[str, Any]:
    from sim.garage.options import new_model

    rows = []
    for sensor in sensors:
        figures: dict[int, Trained] = {}
        for count in (1, processes):
            model = new_model(f"bench-{sensor}-{count}", sensors=[sensor])
            figures[count] = train_model(model.name, seconds / 60.0, ["--processes", str(count)])
        one, many = figures[1], figures[processes]
        rows.append(
            {
                "sensor": sensor,
                "steps_per_second_1": _rate(one),
                f"steps_per_second_{processes}": _rate(many),
                "ratio": _rate(many) / max(_rate(one), 1e-9),
                "last_evaluation_1": _last_evaluation(one),
                f"last_evaluation_{processes}": _last_evaluation(many),
                "ended": [one.ended, many.ended],
            }
        )
    return {"seconds": seconds, "processes": processes, "rows": rows}


def _rate(trained: Trained) -> float:
    return trained.steps / trained.seconds if trained.seconds > 0 else 0.0


def _last_evaluation(trained: Trained) -> str:
    if not trained.evaluations:
        return "-"
    _, laps, trials = trained.evaluations[-1]
    return f"{laps}/{trials} laps"


def _print(result: dict[str, Any]) -> None:
    n = result["processes"]
    print(f"one training for {result['seconds']:g} s: env steps per second, 1 vs {n} processes")
    print(f"{'sensor':<8} {'1 process':>10} {f'{n} processes':>12} {'ratio':>6}  last evaluation")
    for row in result["rows"]:
        print(
            f"{row['sensor']:<8} {row['steps_per_second_1']:>10,.0f} "
            f"{row[f'steps_per_second_{n}']:>12,.0f} {row['ratio']:>6.2f}  "
            f"{row['last_evaluation_1']} / {row[f'last_evaluation_{n}']}"
        )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.training.processes")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--sensor", action="append", choices=SENSORS)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--keep", help="keep the trained models in this folder")
    args = parser.parse_args(argv)
    if args.seconds <= 0 or args.processes < 2:
        parser.error("--seconds must be more than 0 and --processes 2 or more")
    with bench_home(args.keep):
        result = run(args.sensor or SENSORS, args.seconds, args.processes)
    print_result(result, args.json, _print)
    return 0


if __name__ == "__main__":
    sys.exit(main())

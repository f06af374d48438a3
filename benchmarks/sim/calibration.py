"""Calibration benchmark: how closely racer-tui's car follows DeepRacer's own sim-traces.

    python -m benchmarks.sim.calibration [TRACE ...] [--car default|simapp4|both] [--json]

Replays the commands of real DeepRacer sim-traces open-loop through racer-tui's car
(`sim.calibration`) and prints, beside DeepRacer's own figures: the path curvature at
steady steering per steering angle and speed (and their ratio), the steering lag, the
speed reached over the commanded one, and the median gap of the reported point after 1 s
and 2 s of replay from the trace's pose and speed. Targets: curvature within 10 % of
DeepRacer's in every bin, gaps under 0.2 m and 0.5 m. Figures are printed, never judged
by the exit code.

A TRACE is a sim-trace CSV or a folder searched for them; several are pooled. Without one,
the console evaluation trace in `../shared/deepracer/` is used when it is there.

DeepRacer's simulator has two cars (`sim.physics.car`): models of metadata version 5 or more run
on the kinematics car racer-tui drives ("default"); older ones (the shared console trace,
simapp 4.0) on a slower-steering car ("simapp4"). Both are replayed unless `--car` says.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sim.calibration import CURVATURE_TOLERANCE, GAP_TARGETS, Calibration, calibrate
from sim.deepracer.files import DeepRacerFileError, SimTraceRow, read_sim_trace
from sim.foundation.plural import counted
from sim.physics.car import DEEPRACER_CAR, SIMAPP4_CAR, CarSpec

SHARED_TRACE = (
    Path(__file__).resolve().parents[3]  # beside the repository: benchmarks/sim/ is two deep
    / "shared/deepracer/console-logs/sim-trace/evaluation/0-iteration.csv"
)
CARS: dict[str, tuple[CarSpec, str]] = {
    "default": (DEEPRACER_CAR, "racer-tui's car: DeepRacer's simapp 5+ kinematics car"),
    "simapp4": (SIMAPP4_CAR, "DeepRacer's simapp 3-4 car (models of metadata version < 5)"),
}


def trace_files(arguments: Sequence[str]) -> list[Path]:
    files: list[Path] = []
    for argument in arguments:
        path = Path(argument)
        if path.is_dir():
            found = sorted(path.rglob("*.csv"))
            if not found:
                raise DeepRacerFileError(f"{path}: no sim-trace CSV files in this folder.")
            files.extend(found)
        elif path.is_file():
            files.append(path)
        else:
            raise DeepRacerFileError(f"{path}: no such file or folder.")
    return files


def figures(calibration: Calibration) -> dict[str, Any]:
    def rounded(value: float, digits: int = 3) -> float | None:
        return None if math.isnan(value) else round(value, digits)

    return {
        "runs": calibration.runs,
        "intervals": calibration.intervals,
        "windows": calibration.windows,
        "curvature": [
            {
                "steering_deg": b.steering_deg,
                "speed_m_s": b.speed,
                "samples": b.samples,
                "deepracer_per_m": rounded(b.deepracer),
                "racer_tui_per_m": rounded(b.racer_tui),
                "ratio": rounded(b.ratio),
            }
            for b in calibration.curvature
        ],
        "lag_s": {
            "deepracer": rounded(calibration.lag_deepracer),
            "racer_tui": rounded(calibration.lag_racer_tui),
        },
        "speed_ratio": {
            "deepracer": rounded(calibration.speed_ratio_deepracer),
            "racer_tui": rounded(calibration.speed_ratio_racer_tui),
        },
        "gap_m": {f"{at:g}s": rounded(gap) for at, gap in calibration.gaps.items()},
        "targets": {
            "curvature_ratio_within": CURVATURE_TOLERANCE,
            "gap_m": {f"{at:g}s": target for at, target in GAP_TARGETS.items()},
        },
        "curvature_within_tolerance": calibration.curvature_within_tolerance,
        "gaps_within_targets": calibration.gaps_within_targets,
        "meets_targets": calibration.meets_targets,
    }


def table(name: str, description: str, calibration: Calibration) -> str:
    def mark(ok: bool) -> str:
        return "ok" if ok else "MISSED"

    lines = [
        f"{name}: {description}",
        f"  {calibration.runs} runs of driving, {calibration.intervals} intervals, "
        f"{calibration.windows} replay windows",
        "  curvature at steady steering   DeepRacer  racer-tui  ratio",
    ]
    for b in calibration.curvature:
        within = abs(b.ratio - 1.0) <= CURVATURE_TOLERANCE
        label = f"{b.steering_deg:>2} deg at {b.speed} m/s ({b.samples})"
        lines.append(
            f"    {label:<28}{b.deepracer:>7.2f} /m {b.racer_tui:>7.2f} /m"
            f"  {b.ratio:5.2f} {mark(within)}"
        )
    lines += [
        f"  steering lag (63 %)           {calibration.lag_deepracer:>7.2f} s  "
        f"{calibration.lag_racer_tui:>7.2f} s",
        f"  speed reached / commanded     {calibration.speed_ratio_deepracer:>9.3f}"
        f"  {calibration.speed_ratio_racer_tui:>9.3f}",
    ]
    for at, target in GAP_TARGETS.items():
        gap = calibration.gaps[at]
        lines.append(
            f"  median gap after {at:g} s       {gap:>9.3f} m (target < {target} m) "
            f"{mark(gap < target)}"
        )
    lines.append(f"  meets the targets: {'yes' if calibration.meets_targets else 'no'}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sim.calibration",
        description="Replay DeepRacer sim-traces through racer-tui's car and compare.",
    )
    parser.add_argument("traces", nargs="*", metavar="TRACE", help="sim-trace CSV or folder")
    parser.add_argument("--car", choices=[*CARS, "both"], default="both")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    args = parser.parse_args(argv)
    arguments = args.traces or ([str(SHARED_TRACE)] if SHARED_TRACE.is_file() else [])
    if not arguments:
        print(
            "No sim-trace given and ../shared/deepracer is absent: name a DeepRacer "
            "sim-trace CSV or folder.",
            file=sys.stderr,
        )
        return 2
    try:
        files = trace_files(arguments)
        traces: list[list[SimTraceRow]] = [read_sim_trace(path) for path in files]
    except DeepRacerFileError as error:
        print(error, file=sys.stderr)
        return 2
    names = list(CARS) if args.car == "both" else [args.car]
    try:
        results = {name: calibrate(traces, CARS[name][0]) for name in names}
    except ValueError as error:
        print(f"{', '.join(arguments)}: {error}.", file=sys.stderr)
        return 2
    if args.json:
        report = {
            "traces": [str(path) for path in files],
            "rows": sum(len(rows) for rows in traces),
            "cars": [
                {"car": name, "description": CARS[name][1], **figures(result)}
                for name, result in results.items()
            ],
        }
        print(json.dumps(report, indent=2))
    else:
        print(f"DeepRacer sim-traces: {counted(len(files), 'file')}, {sum(map(len, traces))} rows")
        for name, result in results.items():
            print()
            print(table(name, CARS[name][1], result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

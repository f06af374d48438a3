"""Start-up benchmark: how long each command takes from a cold process, and what it imports.

    python -m benchmarks.app.startup [--repeat 5] [--json]

Each command runs in a fresh Python process, as a racer's shell runs it, in a scratch
racer-tui home: `--repeat` times for the wall clock (the best and the median are shown),
then once under `python -X importtime` for where its import time goes, by top-level package
(the sum of each package's modules' own times) and whether it loaded the heavy parts it
should not need (Textual, torch, stable-baselines3). The race command's target, 1.0 s cold
start to result, is the speed issue's; figures are printed, never judged.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

COMMANDS: dict[str, tuple[str, ...]] = {
    "race": ("--race", "reference", "--track", "reinvent_base", "--json"),
    "leaderboard": ("leaderboard",),
    "model list": ("model", "list"),
    "tracks list": ("tracks", "list"),
    "help": ("--help",),
}
TARGET_SECONDS = {"race": 1.0}
HEAVY = ("textual", "torch", "stable_baselines3", "scipy", "shapely", "gymnasium")
TOP_PACKAGES = 6


@dataclass(frozen=True)
class Startup:
    command: str
    best_seconds: float
    median_seconds: float
    import_seconds: float
    by_package: dict[str, float]  # the heaviest packages' own import seconds
    heavy: list[str]  # heavy packages the command loaded
    target_seconds: float | None


def _script(args: Sequence[str]) -> str:
    return f"from racer_tui.cli.main import main\nraise SystemExit(main({list(args)!r}))\n"


def _run(args: Sequence[str], env: dict[str, str], importtime: bool = False) -> tuple[float, str]:
    command = [sys.executable, *(["-X", "importtime"] if importtime else []), "-c", _script(args)]
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    seconds = time.perf_counter() - started
    if done.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(args)} exited {done.returncode}: {done.stderr[-500:]}")
    return seconds, done.stderr


def imports_by_package(importtime_log: str) -> dict[str, float]:
    """Seconds of each top-level package's own import time, from `-X importtime` lines
    ("import time: self [us] | cumulative | name")."""
    totals: dict[str, float] = defaultdict(float)
    for line in importtime_log.splitlines():
        if not line.startswith("import time:"):
            continue
        parts = line[len("import time:") :].split("|")
        if len(parts) != 3 or not parts[0].strip().isdigit():
            continue  # the header line
        package = parts[2].strip().split(".")[0]
        totals[package] += int(parts[0]) / 1e6
    return dict(totals)


def measure(name: str, args: Sequence[str], repeat: int, env: dict[str, str]) -> Startup:
    _run(args, env)  # the first run fills the disk cache and the scratch home
    walls = [_run(args, env)[0] for _ in range(repeat)]
    _, log = _run(args, env, importtime=True)
    packages = imports_by_package(log)
    heaviest = dict(sorted(packages.items(), key=lambda item: -item[1])[:TOP_PACKAGES])
    return Startup(
        command=name,
        best_seconds=min(walls),
        median_seconds=statistics.median(walls),
        import_seconds=sum(packages.values()),
        by_package={package: round(seconds, 4) for package, seconds in heaviest.items()},
        heavy=[package for package in HEAVY if package in packages],
        target_seconds=TARGET_SECONDS.get(name),
    )


def run(repeat: int) -> list[Startup]:
    with tempfile.TemporaryDirectory(prefix="racer-startup-") as home:
        env = {**os.environ, "RACER_TUI_HOME": home}
        return [measure(name, args, repeat, env) for name, args in COMMANDS.items()]


def _print(results: list[Startup]) -> None:
    print("cold start of each command (fresh process), and where its imports go")
    print(f"{'command':<12} {'best s':>7} {'median s':>9} {'imports s':>10} {'target':>7}  heavy")
    for r in results:
        target = f"{r.target_seconds:g} s" if r.target_seconds is not None else "-"
        heavy = ", ".join(r.heavy) or "none"
        print(
            f"{r.command:<12} {r.best_seconds:>7.3f} {r.median_seconds:>9.3f} "
            f"{r.import_seconds:>10.3f} {target:>7}  {heavy}"
        )
        shares = ", ".join(
            f"{name} {seconds * 1000:.0f} ms" for name, seconds in r.by_package.items()
        )
        print(f"{'':<12} own import time by package: {shares}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.app.startup")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be 1 or more")
    results = run(args.repeat)
    if args.json:
        rows: list[dict[str, Any]] = [asdict(r) for r in results]
        sys.stdout.write(json.dumps(rows, indent=2) + "\n")
    else:
        _print(results)
    return 0


if __name__ == "__main__":
    sys.exit(main())

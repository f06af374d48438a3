"""What the training benchmarks share: models trained in child processes side by side, a
scratch data folder, and a result printed as JSON or as a table."""

from __future__ import annotations

import json
import os
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, TypeVar

Item = TypeVar("Item")


def train_side_by_side(items: Sequence[Item], train: Callable[[Item], object]) -> bool:
    """`train` each item, two at once when the machine has two cores or more (each
    training child takes one); True when they ran side by side."""
    side_by_side = (os.cpu_count() or 1) >= 2
    with ThreadPoolExecutor(max_workers=2 if side_by_side else 1) as pool:
        list(pool.map(train, items))
    return side_by_side


@dataclass
class Trained:
    """What a training child reported: its steps and seconds, how it ended, and (seconds
    into training, laps, trials) of each of its own evaluations."""

    steps: int = 0
    seconds: float = 0.0
    ended: str = ""
    evaluations: list[tuple[float, int, int]] = field(default_factory=list)


def train_model(model: str, minutes: float, extra: Sequence[str] = ("--processes", "1")) -> Trained:
    """Train garage model `model` for `minutes` in a child process, as the app does
    (`extra`: more of the child's options). A benchmark's training takes one core unless
    it says otherwise, whatever the machine has (the figures' targets are per core)."""
    from sim.training import events
    from sim.training.launcher import TrainingProcess

    trained = Trained()
    process = TrainingProcess.start(model, minutes, extra)
    for event in process.events():
        if isinstance(event, events.Update):
            trained.steps, trained.seconds = event.total_steps, event.elapsed
        elif isinstance(event, events.Evaluation):
            trained.evaluations.append((event.elapsed, event.laps, event.trials))
        elif isinstance(event, events.Ended):
            trained.ended = event.kind
    process.wait()
    return trained


@contextmanager
def bench_home(keep: str | None) -> Iterator[None]:
    """Models made inside live in `keep`, or in a scratch folder removed afterwards."""
    with tempfile.TemporaryDirectory(prefix="racer-bench-") as scratch:
        os.environ["RACER_TUI_HOME"] = keep or scratch
        yield


def print_result(
    result: dict[str, Any], as_json: bool, table: Callable[[dict[str, Any]], None]
) -> None:
    if as_json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
    else:
        table(result)

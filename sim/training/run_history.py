"""A model's training curves across all its runs: the PPO updates and system readings.

DeepRacer's TrainingMetrics.json keeps every episode, so reward, progress and lap-time
curves survive a restart of the app and a resumed training; entropy, steps per second and
CPU are not in it. The trainer appends each `update` and `system` event to
`ModelFolder.training_history` (one JSON line each, the events' own format) as it emits
it, so the charts read a model's whole history back: after a restart, on resume, when
another model is selected. About one line every two seconds of training: a three-hour run
writes well under a megabyte, and reading keeps only the last `MAX_EVENTS`.

A line cut short by a killed run, or any line that is not a valid event, is skipped.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path

from sim.training import events

# Enough for every chart point (racer_tui.app.widgets.chart.MAX_POINTS is 5,000) of both kinds.
MAX_EVENTS = 20_000
HISTORY_KINDS = (events.Update, events.System)


class RunHistory:
    """Appends a run's updates and system readings to the model's history file."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def record(self, event: events.Event) -> None:
        if not isinstance(event, HISTORY_KINDS):
            return
        with self.path.open("a", encoding="utf-8") as out:
            out.write(events.encode(event) + "\n")


def read_history(path: Path) -> list[events.Update | events.System]:
    """The model's updates and system readings, oldest first (the last MAX_EVENTS)."""
    if not path.is_file():
        return []
    kept: deque[events.Update | events.System] = deque(maxlen=MAX_EVENTS)
    with path.open("rb") as handle:
        for line in handle:
            try:
                event = events.decode(line.strip())
            except events.EventError:
                continue
            if isinstance(event, events.Update | events.System):
                kept.append(event)
    return list(kept)

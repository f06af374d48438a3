"""The training event stream: every event survives a JSON line, bad lines are refused."""

from __future__ import annotations

import json
import math

import pytest

from sim.foundation.remedies import Fix
from sim.training import events

SAMPLES: list[events.Event] = [
    events.Started(0.0, "m", "hairpin-circuit", ("vector",), 64, "scratch", 0, 60.0, 123),
    events.Episode(1.5, 7, 0, 12.5, 43.2, None, "Off track", 41),
    events.Episode(2.5, 8, 0, 99.0, 100.0, 9.8, "Lap complete", 147),
    events.Update(3.0, 1, 2048, 80, 2.1, -0.01, 0.9, 0.01, 0.1, 6000.0, 80, 5.0, 12.0, 0, None),
    events.Evaluation(3.1, 1, 2048, 5, 2, 61.0, 9.9, (9.9, 10.2), ("Lap complete",) * 2, True),
    events.System(4.0, 95.5, 380.2),
    events.Checkpoint(4.1, 1, 2048, "checkpoints/latest.safetensors"),
    events.Ended(5.0, "stopped", "training was stopped", 2048, 80, 61.0, None),
    events.Ended(
        0.0, "failed", "p; run `racer-tui x`.", 0, 0, 0.0, None, problem="p", fix="TRAIN_MODEL"
    ),
]


@pytest.mark.parametrize("event", SAMPLES, ids=events.type_of)
def test_every_event_round_trips_through_one_json_line(event: events.Event) -> None:
    line = events.encode(event)
    assert "\n" not in line
    assert json.loads(line)["type"] == events.type_of(event)
    assert events.decode(line) == event


def test_each_ending_keeps_its_kind() -> None:
    for kind in events.ENDINGS:
        ended = events.Ended(1.0, kind, "why", 1, 1, 0.0, None)
        line = events.encode(ended)
        assert json.loads(line)["type"] == kind
        assert events.decode(line) == ended


def test_a_failure_carries_its_remedy_apart_and_older_lines_still_read() -> None:
    ended = events.Ended(0.0, "failed", "p; run it.", 0, 0, 0.0, None, problem="p", fix="RENAME")
    decoded = events.decode(events.encode(ended))
    assert isinstance(decoded, events.Ended) and decoded.remedy is Fix.RENAME
    # A line of a racer-tui before remedies travelled: no remedy, the message as it was.
    older = '{"type":"failed","elapsed":0,"message":"m","total_steps":0,"episodes":0,'
    older += '"best_progress":0,"best_lap":null}'
    decoded = events.decode(older)
    assert isinstance(decoded, events.Ended)
    assert (decoded.message, decoded.problem, decoded.remedy) == ("m", "", None)
    # A remedy this racer-tui does not know is no event.
    with pytest.raises(events.EventError, match="names no remedy"):
        events.decode(older[:-1] + ',"problem":"p","fix":"DELETE_EVERYTHING"}')


def test_a_nan_figure_travels_as_null_and_comes_back_as_nan() -> None:
    update = events.Update(1.0, 1, 10, 1, math.nan, 0, 0, 0, 0, 1, 1, 0, 0, 0, None)
    line = events.encode(update)
    assert json.loads(line)["entropy"] is None
    decoded = events.decode(line)
    assert isinstance(decoded, events.Update)
    assert math.isnan(decoded.entropy)


@pytest.mark.parametrize(
    "line",
    [
        "not json",
        "[1, 2]",
        '{"type": "nonsense", "elapsed": 1}',
        '{"type": "system", "elapsed": 1.0, "cpu_percent": 3.0}',
        '{"type": "system", "elapsed": 1.0, "cpu_percent": "high", "rss_mb": 1.0}',
        '{"type": "checkpoint", "elapsed": 1.0, "iteration": 1.5, "total_steps": 1, "file": "x"}',
        '{"type": "episode", "elapsed": 1, "episode": true, "car": 0, "reward": 1, '
        '"progress": 1, "lap_time": null, "status": "Off track", "steps": 3}',
        '{"type": "system", "elapsed": 1.0, "cpu_percent": 1.0, "rss_mb": 1.0, "pad": "'
        + "x" * 70_000
        + '"}',
    ],
)
def test_decode_rejects_lines_that_are_not_valid_events(line: str) -> None:
    with pytest.raises(events.EventError):
        events.decode(line)

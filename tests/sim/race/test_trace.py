"""Race traces: written as DeepRacer sim-trace CSV, read back for replays and ghosts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim.deepracer.files import SIM_TRACE_COLUMNS, DeepRacerFileError, read_sim_trace
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.race.trace import RaceTrace, TraceError
from sim.tracks.catalog import resolve_track
from tests.sim.race.drivers import ScriptedDriver


@pytest.fixture(scope="module")
def trace() -> RaceTrace:
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RaceRules(window_seconds=20.0), ScriptedDriver(track, (150,)))
    assert result.trace is not None
    return result.trace


def test_the_trace_has_a_row_per_tick_and_starts_on_the_line(trace: RaceTrace) -> None:
    assert len(trace) == 20 * 15 + 1  # the start row, then 15 rows a second
    statuses = trace.statuses()
    assert statuses[0] == "prepare" and trace.t[0] == 0.0
    assert statuses[-1] == "time_up"
    assert {"in_progress", "lap_complete", "off_track", "pause"} <= set(statuses)
    assert np.all(np.diff(trace.t) > 0)
    # The window cuts the lap after the last one completed (the one with the penalty).
    completed = statuses.count("lap_complete")
    assert completed >= 1
    assert trace.lap[0] == 1 and trace.lap[-1] == completed + 1
    assert trace.offtrack.sum() == 1


def test_sim_trace_csv_round_trip(trace: RaceTrace, tmp_path: Path) -> None:
    path = tmp_path / "race.csv"
    trace.write_csv(path)
    header = path.read_text().splitlines()[0].split(",")
    assert tuple(header) == SIM_TRACE_COLUMNS
    rows = read_sim_trace(path)
    assert len(rows) == len(trace)
    assert rows[-1].done and not rows[0].done
    assert rows[0].episode_status == "prepare"
    assert sum(row.pause_duration for row in rows) == pytest.approx(3.0)
    # DeepRacer numbers episodes from 0: here, the lap in progress.
    completed = trace.statuses().count("lap_complete")
    assert [rows[0].episode, rows[-1].episode] == [0, completed]

    back = RaceTrace.read_csv(path)
    assert back.statuses() == trace.statuses()
    assert np.array_equal(back.x, trace.x) and np.array_equal(back.y, trace.y)
    assert np.array_equal(back.heading, trace.heading)
    assert np.array_equal(back.lap, trace.lap)
    assert np.array_equal(back.offtrack, trace.offtrack)
    assert np.array_equal(back.action, trace.action)
    assert np.allclose(back.t, trace.t, atol=5e-4)
    # Speed is not a sim-trace column: derived from the path, close to the real one.
    moving = (np.array(trace.statuses()) == "in_progress") & (trace.speed > 0.5)
    assert np.median(back.speed[moving] / trace.speed[moving]) == pytest.approx(1.0, abs=0.05)
    assert back.track_length == pytest.approx(trace.track_length)


def test_a_trace_that_is_not_one_race_is_refused(tmp_path: Path) -> None:
    with pytest.raises(TraceError, match="no rows"):
        RaceTrace.from_sim_trace_rows([])
    path = tmp_path / "bad.csv"
    path.write_text("not,a,trace\n1,2,3\n")
    with pytest.raises(DeepRacerFileError):
        RaceTrace.read_csv(path)


def test_deepracer_evaluation_traces_read_as_race_traces(deepracer_dir: Path) -> None:
    path = deepracer_dir / "console-logs" / "sim-trace" / "evaluation" / "0-iteration.csv"
    trace = RaceTrace.read_csv(path)
    assert len(trace) == 737
    assert trace.statuses().count("lap_complete") == 3

"""A physical car's heat written down input by input, so a killed racer-tui loses nothing:
the heat comes back as it was, paused, with its laps, resets and start."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from league.timekeeper.heat import Phase, TimekeptHeat
from league.timekeeper.journal import HeatJournal, resume_heat, take_input
from sim.race.rules import RaceRules

RULES = RaceRules(window_seconds=60.0, penalty_seconds=2.0)
HEAT = "01JDR0000000000000000HEAT1"


def timed(path: Path, inputs: list[tuple[str, float]], beat: float | None = None) -> TimekeptHeat:
    """A heat given `inputs` with its journal at `path`, a heartbeat at `beat`."""
    heat = TimekeptHeat(RULES)
    journal = HeatJournal(path, HEAT)
    for kind, at in inputs:
        take_input(heat, kind, at)
        journal.took(kind, at, heat)
    if beat is not None:
        journal.heartbeat(beat)
    return heat


def test_a_heat_comes_back_paused_where_its_last_heartbeat_left_it(tmp_path: Path) -> None:
    path = tmp_path / "heat.json"
    before = timed(path, [("start_or_pause", 0.0), ("reset", 4.0), ("capture", 10.0)], 15.5)
    resumed = resume_heat(path, HEAT, RULES)
    assert resumed is not None
    heat = resumed.heat
    assert heat.phase is Phase.PAUSED and resumed.at == 15.5
    assert heat.lap_records() == before.lap_records()  # lap 1: 10 s and a reset (+2 s)
    assert heat.started_at == before.started_at
    assert heat.time_left(1000.0) == pytest.approx(60.0 - 15.5)  # stopped: time stands
    assert heat.lap_clock(1000.0) == pytest.approx(5.5)
    # It goes on from there, and its journal with it.
    resumed.accept()
    for kind, at in (("start_or_pause", 20.0), ("capture", 29.5)):
        take_input(heat, kind, at)
        resumed.journal.took(kind, at, heat)
    assert [lap.raw_seconds for lap in heat.lap_records()] == [10.0, 15.0]
    again = resume_heat(path, HEAT, RULES)
    assert again is not None and len(again.heat.laps) == 2


def test_a_resumed_heat_keeps_every_lap_to_the_last_digit(tmp_path: Path) -> None:
    # The host walk: a lap captured live as 0:05.010 read 0:05.011 once the heat came back
    # (its input times were kept to 0.1 ms). These two inputs' lap reads 6.158 s, and 6.159 s
    # from times rounded to 0.1 ms.
    path = tmp_path / "heat.json"
    inputs = [("start_or_pause", 1.5410462796616011), ("capture", 7.699516073460717)]
    before = timed(path, inputs, 9.000000001)
    assert f"{before.lap_records()[0].time_seconds:.3f}" == "6.158"
    resumed = resume_heat(path, HEAT, RULES)
    assert resumed is not None
    assert resumed.heat.lap_records() == before.lap_records()


def test_a_heat_whose_race_was_over_comes_back_over_with_its_laps(tmp_path: Path) -> None:
    path = tmp_path / "heat.json"
    inputs = [("start_or_pause", 0.0), ("capture", 9.0), ("capture", 19.5), ("end", 25.0)]
    before = timed(path, inputs)
    resumed = resume_heat(path, HEAT, RULES)
    assert resumed is not None and resumed.heat.phase is Phase.OVER
    assert resumed.heat.lap_records() == before.lap_records()


def test_a_recorded_or_abandoned_heat_has_nothing_to_resume(tmp_path: Path) -> None:
    path = tmp_path / "heat.json"
    timed(path, [("start_or_pause", 0.0)])
    journal = resume_heat(path, HEAT, RULES)
    assert journal is not None
    journal.journal.forget()
    assert not path.exists() and resume_heat(path, HEAT, RULES) is None


HEADER = json.dumps({"format": 1, "heat_id": HEAT, "started_at": "2026-11-25T19:00:00.000Z"})


def lines(*items: object, header: str = HEADER) -> str:
    return "\n".join([header, *(json.dumps(item) for item in items)]) + "\n"


def test_a_line_torn_by_a_kill_is_left_out_and_the_rest_stands(tmp_path: Path) -> None:
    path = tmp_path / "heat.json"
    text = lines(["start_or_pause", 0.0, None], ["capture", 10.0, None], ["beat", 12.0, None])
    path.write_text(text + '["reset", 12.5, nu')
    resumed = resume_heat(path, HEAT, RULES)
    assert resumed is not None and resumed.at == 12.0
    assert len(resumed.heat.laps) == 1 and resumed.heat.resets == 0


@pytest.mark.parametrize(
    "content",
    [
        lines(["start_or_pause", 0.0, None], header=HEADER.replace(HEAT, "01JDR0000000OTHER")),
        lines(["capture", 10.0, None]),  # does not replay: the race never started
        lines(["start_or_pause", 5.0, None], ["reset", 1.0, None]),  # time runs backwards
        lines(["explode", 1.0, None]),
        lines(["start_or_pause", 1e300, None]),
        lines(["start_or_pause", 0.0, None], ["strike", 1.0, True]),
        lines(),
        lines(["start_or_pause", 0.0, None], header=HEADER.replace('"format": 1', '"format": 2')),
        "not json\n" + lines(["start_or_pause", 0.0, None]),
        "[" * 100_000 + "\n",
        "x" * 3_000_000,
        "\x00\xff\n",
    ],
)
def test_a_damaged_or_foreign_journal_is_no_journal(tmp_path: Path, content: str) -> None:
    path = tmp_path / "heat.json"
    path.write_text(content, encoding="utf-8", errors="surrogateescape")
    assert resume_heat(path, HEAT, RULES) is None
    assert resume_heat(tmp_path / "missing.json", HEAT, RULES) is None

"""What the app remembers of a session's races: every race, and the newest ones' traces."""

from __future__ import annotations

from dataclasses import replace

from racer_tui.app.application import create_app
from racer_tui.app.session import TRACES_KEPT, keep_race, session_races
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track


def test_a_long_session_keeps_every_race_but_only_the_newest_traces() -> None:
    app = create_app()
    raced = run_race(resolve_track("beginner-oval"), RaceRules(window_seconds=5.0), keep_trace=True)
    assert raced.trace is not None
    for number in range(TRACES_KEPT + 3):
        keep_race(app, replace(raced, result_id=f"race-{number}"))
    keep_race(app, None)  # a race left early adds nothing
    races = session_races(app)
    assert [race.result_id for race in races] == [f"race-{n}" for n in range(TRACES_KEPT + 3)]
    assert [race.trace is not None for race in races] == [False] * 3 + [True] * TRACES_KEPT
    assert all(race.laps == raced.laps for race in races)  # laps and scores stay

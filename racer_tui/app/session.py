"""What one run of the app remembers between its sections: the races run in it, and who
is racing (asked the first time something is submitted).

A race can start from the Races section or from a model in the Garage; either way it
belongs in "Races this session", where it can be replayed, raced as a ghost or submitted
to the league. The list lives with the app (weakly: a finished app, as in tests, lets go),
not with a screen, because the Races screen may not exist yet when the Garage races.

A race's trace (every car's pose at every step, what a replay and a ghost need) is a few
megabytes for a 4-minute race, and a league night's app stays open for hours: only the
newest `TRACES_KEPT` races of the session keep theirs in memory. Older ones keep their laps
and scores; a race that was submitted or recorded in the league still replays from there.
"""

from __future__ import annotations

from typing import Any
from weakref import WeakKeyDictionary

from textual.app import App

from sim.race.result import RaceResult

TRACES_KEPT = 12
_RACES: WeakKeyDictionary[App[Any], list[RaceResult]] = WeakKeyDictionary()
_RACER: WeakKeyDictionary[App[Any], str] = WeakKeyDictionary()


def session_races(app: App[Any]) -> list[RaceResult]:
    """The races finished in this app run (the list itself: append to it)."""
    return _RACES.setdefault(app, [])


def keep_race(app: App[Any], result: RaceResult | None) -> None:
    """The RaceScreen callback for a race run anywhere in the app (None: it was left early)."""
    if result is None:
        return
    races = session_races(app)
    races.append(result)
    traced = [index for index, race in enumerate(races) if race.trace is not None]
    for index in traced[:-TRACES_KEPT]:
        races[index] = races[index].with_trace(None)


def session_racer(app: App[Any]) -> str | None:
    """The racer confirmed in this app run, if anyone has said yet."""
    return _RACER.get(app)


def remember_racer(app: App[Any], racer: str) -> None:
    _RACER[app] = racer

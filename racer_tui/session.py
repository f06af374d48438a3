"""What one run of the app remembers between its sections: the races run in it.

A race can start from the Races section or from a model in the Garage; either way it
belongs in "Races this session", where it can be replayed, raced as a ghost or submitted
to the league. The list lives with the app (weakly: a finished app, as in tests, lets go),
not with a screen, because the Races screen may not exist yet when the Garage races.
"""

from __future__ import annotations

from typing import Any
from weakref import WeakKeyDictionary

from textual.app import App

from sim.race.result import RaceResult

_RACES: WeakKeyDictionary[App[Any], list[RaceResult]] = WeakKeyDictionary()


def session_races(app: App[Any]) -> list[RaceResult]:
    """The races finished in this app run (the list itself: append to it)."""
    return _RACES.setdefault(app, [])


def keep_race(app: App[Any], result: RaceResult | None) -> None:
    """The RaceScreen callback for a race run anywhere in the app (None: it was left early)."""
    if result is not None:
        session_races(app).append(result)

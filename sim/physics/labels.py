"""Which simulator's physics produced a lap: lap times of different physics never meet on
one leaderboard.

racer-tui's own physics is versioned by `sim.physics.car.PHYSICS_VERSION` ("racer-tui/4"); laps
timed by AWS DeepRacer's own simulator (console and DeepRacer-for-Cloud evaluations) are
"deepracer". Laps of a physical car, timed by a league's timekeeper, are "physical": a real
track, not a simulator, so they too are ranked apart. Results recorded before physics was
recorded are racer-tui's version 1, or DeepRacer's when they came from its files. Whether a
string is a label at all is DeepRacer-file vocabulary (`sim.deepracer.vocabulary.is_physics`).
"""

from __future__ import annotations

from typing import Final

from sim.physics.car import PHYSICS_VERSION

CURRENT: Final = f"racer-tui/{PHYSICS_VERSION}"
BEFORE_VERSIONING: Final = "racer-tui/1"
DEEPRACER: Final = "deepracer"
PHYSICAL: Final = "physical"


def describe(physics: str) -> str:
    """ "DeepRacer's simulator", "racer-tui physics 4"."""
    if physics == DEEPRACER:
        return "DeepRacer's simulator"
    if physics == PHYSICAL:
        return "a physical car on a real track"
    return f"racer-tui physics {physics.removeprefix('racer-tui/')}"


def board_suffix(physics: str) -> str:
    """What a leaderboard adds to a track's name for laps of other physics than today's
    (" (DeepRacer)", " (physics 1)"): they are ranked on a board of their own, and the
    name says which, briefly enough for a table column."""
    if physics == CURRENT:
        return ""
    if physics == DEEPRACER:
        return " (DeepRacer)"
    if physics == PHYSICAL:
        return " (physical)"
    return f" (physics {physics.removeprefix('racer-tui/')})"

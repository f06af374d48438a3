"""A physical car as a night's entrant: the model spec `physical`, or `physical:NAME` to
tell two cars apart (the name a car's sticker or its DeepRacer host name gives)."""

from __future__ import annotations

from typing import Final

from league.errors import LeagueError
from sim.foundation.plain_names import MAX_NAME_LENGTH, is_plain_name
from sim.foundation.remedies import echoed

PHYSICAL: Final = "physical"
_PREFIX: Final = f"{PHYSICAL}:"


def is_physical(spec: str) -> bool:
    return spec == PHYSICAL or spec.startswith(_PREFIX)


def physical_spec(spec: str) -> str:
    """`spec` checked as a physical car's: `physical`, or `physical:NAME` with a plain name."""
    if spec == PHYSICAL:
        return spec
    name = spec.removeprefix(_PREFIX).strip()
    if not is_plain_name(name):
        raise LeagueError(
            f"{echoed(name)} is not a car name: after 'physical:' give 1 to {MAX_NAME_LENGTH} "
            "printable characters, or write just 'physical'."
        )
    return _PREFIX + name


def car_name(spec: str) -> str:
    """How the car is named on the board: "physical car", or its own name."""
    return spec.removeprefix(_PREFIX) if spec.startswith(_PREFIX) else "physical car"

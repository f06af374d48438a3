"""How the command line and the app name a head-to-head race's cars and say what happened
between them: one wording on both."""

from __future__ import annotations

from collections.abc import Mapping

from sim.race.head_to_head import Incident


def car_name(racer: str, model_name: str) -> str:
    """The racer, and the model when the racer is not simply the model's name."""
    return racer if racer == model_name else f"{racer} ({model_name})"


def incident_sentence(incident: Incident, names: Mapping[int, str]) -> str:
    """A crash or overtake as a commentator says it (`names`: by grid index), without its
    clock."""
    car, other = names[incident.car], names[incident.other]
    if incident.kind == "crash":
        return f"{car} ran into {other} and is held"
    return f"{car} passed {other}"

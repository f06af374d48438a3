"""Errors of the training package, importable without torch (the CLI lists them)."""

from __future__ import annotations

from sim.deepracer.files import DeepRacerFileError
from sim.foundation.remedies import Fix, RemedyError
from sim.garage.folder import ModelError
from sim.reward.errors import RewardFunctionError
from sim.tracks.errors import TrackError


class PolicyError(RemedyError):
    """A policy file that cannot drive this model; one sentence saying what to do."""


def describe_failure(error: BaseException) -> str:
    """A training failure in the racer's words: racer-tui's own errors are already one
    sentence; anything else is a fault of racer-tui, said as such (the type helps a report)."""
    from sim.training.fleet_parts import PartError

    racers_words = (
        ModelError | PolicyError | DeepRacerFileError | RewardFunctionError | TrackError | PartError
    )
    if isinstance(error, racers_words):
        return str(error)
    return f"racer-tui failed unexpectedly ({type(error).__name__}: {error}); please report it."


def failure_remedy(error: BaseException) -> tuple[str, Fix | None]:
    """The failure without its remedy, and the remedy (for `events.Ended`'s `problem` and
    `fix`), when its message ends in one a front end may offer its own way."""
    if isinstance(error, RemedyError) and error.fix is not None:
        return error.problem, error.fix
    return "", None

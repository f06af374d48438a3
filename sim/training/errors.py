"""Errors of the training package, importable without torch (the CLI lists them)."""

from __future__ import annotations

from sim.remedies import RemedyError


class PolicyError(RemedyError):
    """A policy file that cannot drive this model; one sentence saying what to do."""


def describe_failure(error: BaseException) -> str:
    """A training failure in the racer's words: racer-tui's own errors are already one
    sentence; anything else is a fault of racer-tui, said as such (the type helps a report)."""
    from sim.deepracer_files import DeepRacerFileError
    from sim.garage.folder import ModelError
    from sim.reward_function import RewardFunctionError
    from sim.track_errors import TrackError

    if isinstance(
        error, ModelError | PolicyError | DeepRacerFileError | RewardFunctionError | TrackError
    ):
        return str(error)
    return f"racer-tui failed unexpectedly ({type(error).__name__}: {error}); please report it."

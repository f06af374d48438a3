"""Errors of the training package, importable without torch."""

from __future__ import annotations

from sim.foundation.remedies import Fix, RemedyError


class PolicyError(RemedyError):
    """A policy file that cannot drive this model; one sentence saying what to do."""


def describe_failure(error: BaseException) -> str:
    """A training failure in the racer's words: racer-tui's user errors are already one
    sentence; anything else is a fault of racer-tui, said as such (the type helps a report)."""
    if isinstance(error, RemedyError):
        return str(error)
    return f"racer-tui failed unexpectedly ({type(error).__name__}: {error}); please report it."


def failure_remedy(error: BaseException) -> tuple[str, Fix | None]:
    """The failure without its remedy, and the remedy (for `events.Ended`'s `problem` and
    `fix`), when its message ends in one a front end may offer its own way."""
    if isinstance(error, RemedyError) and error.fix is not None:
        return error.problem, error.fix
    return "", None

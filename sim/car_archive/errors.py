"""The one error type of car archives and their graphs: its message is one sentence for the
racer, naming the file or member and what is wrong."""

from __future__ import annotations

from sim.foundation.remedies import RemedyError


class CarModelError(RemedyError):
    """A car archive, its metadata or its frozen graph cannot be used."""

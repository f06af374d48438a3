"""The track error type, in a module of its own so that naming a track (listing, resolving,
reporting a bad name) never pays for importing the geometry libraries that check arrays."""

from __future__ import annotations

from sim.foundation.remedies import RemedyError


class TrackError(RemedyError):
    """A track file, array or name that cannot be used; the message is meant for the user."""

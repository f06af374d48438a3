"""Sync errors. Every message is one sentence for the user: what is wrong, and what to do.

They all derive from `SyncError`, itself a `RemedyError` (the one root of user errors).
A bad *record* is never an exception that stops a sync: decoding turns it into a
`Quarantined` outcome (see record.py); `RecordInvalidError` is raised only to the code that
builds a record locally, where a bad body is a programming or input error.
"""

from __future__ import annotations

from sim.foundation.remedies import RemedyError


class SyncError(RemedyError):
    """Base of every sync error; the message is a sentence for the user."""


class StoreUrlError(SyncError):
    """A store URL that is not one of the accepted forms."""


class StoreUnavailable(SyncError):  # noqa: N818 (the name the sync design uses)
    """The store cannot be reached (network down, drive not mounted, server stopped)."""


class StoreNotInitialisedError(SyncError):
    """The store is reachable but was never set up with `racer-tui sync init`."""


class StoreFolderMissingError(StoreUnavailable):
    """A shared folder store whose folder is not there, in a folder that is: a new store
    not set up yet, or a shared drive that is not connected (its empty mount point)."""


class StoreAccessDeniedError(SyncError):
    """The store refused us: missing or wrong credentials, or no permission."""


class StoreIncompatibleError(SyncError):
    """The store exists but was made by something else, or by a newer racer-tui."""


class CursorInvalidError(SyncError):
    """A saved pull position that cannot be read; pulling from the start repairs it."""


class RecordInvalidError(SyncError):
    """A record that breaks the shared-record rules (kind, id, body types or sizes)."""


class BundleError(SyncError):
    """A model bundle that cannot be stored or fetched."""


class BundleNotFoundError(BundleError):
    """No bundle with that hash in the bucket."""


class BundleCorruptError(BundleError):
    """A downloaded bundle whose bytes do not match its hash, or that is too large."""

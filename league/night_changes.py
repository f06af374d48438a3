"""A host's changes to a night, as `night_changes` rows name them: an entrant withdrawn
before their heat (target: the entrant), the night deleted before any heat (target: the
night).

league.nights makes them; league.sync.validate checks a pulled one names one of them.
Both read the words here, below either, so that sync's checks need not import the nights.
"""

from __future__ import annotations

WITHDRAW = "withdraw"
DELETE = "delete"
NIGHT_CHANGES = (WITHDRAW, DELETE)

"""A league night under a `verification` rule (sim.race.rules.Verification): which heats
the rule leaves out of its standings, one sentence each.

Racing the simulated heats again before the standings are final is the night's own step
(league.nights.replay_heats): closing a night does it.
"""

from __future__ import annotations

from collections.abc import Collection

from league.nights import Night, heats
from league.ranking import counts_under
from league.store import League
from league.trust.standing import result_standings


def uncounted_heats(league: League, night: Night, local_models: Collection[str] = ()) -> list[str]:
    """One sentence per raced heat that the night's verification rule leaves out of its
    standings, saying why; none when every result counts."""
    required = night.rules.verification
    if not required.requires:
        return []
    raced = [heat for heat in heats(league, night) if heat.race_id is not None]
    found = result_standings(league, [heat.race_id or "" for heat in raced], local_models)
    sentences = []
    for heat in raced:
        standing = found[heat.race_id or ""]
        if counts_under(standing.standing, required):
            continue
        sentences.append(
            f"heat {heat.position} ({heat.entrant.display_name}, {heat.entrant.car}) does not "
            f"count: it is {standing.standing.value} ({standing.why}), and this night counts "
            f"{required.words}."
        )
    return sentences

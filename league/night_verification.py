"""A league night under a `verification` rule (sim.race.rules.Verification): its simulated
heats raced again on the host's machine before the standings are final, and which heats
the rule leaves out of them, one sentence each.

The driver comes from the caller, as for league.trust.replay: racing a trained model
needs torch, which the league package never imports.
"""

from __future__ import annotations

from collections.abc import Collection

from league.nights import Night, heats
from league.ranking import counts_under
from league.store import League
from league.timekeeper.car import is_physical
from league.trust.replay import DriverFor, Verdict, verify_races
from league.trust.standing import result_standings


def replay_heats(league: League, night: Night, driver_for: DriverFor) -> list[str]:
    """Race the night's simulated heats again here (those not verified before) and say,
    one sentence each, which were withdrawn because their laps came out differently."""
    raced = {
        heat.race_id: f"heat {heat.position} ({heat.entrant.display_name}, {heat.entrant.car})"
        for heat in heats(league, night)
        if heat.race_id is not None and not is_physical(heat.entrant.model)
    }
    if not raced:
        return []
    verdicts: list[Verdict] = verify_races(league, driver_for, race_ids=list(raced))
    return [
        f"{raced[verdict.race_id]} is withdrawn: {verdict.detail}."
        for verdict in verdicts
        if verdict.outcome == "differs"
    ]


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

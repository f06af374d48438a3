"""DeepRacer on AWS's verdict on a reward function: its validator's rules read from the text
(`sim.reward.droa_rules`, flake8 run as its own program) and its run of the code, in the
reward check's contained child (`sim.reward.probe`).

Where DRoA stops at the first failing test and says one problem, the verdict lists every
problem the text shows and then the first the run shows, in DRoA's order: the racer fixes
them all at once instead of one per upload. The code runs even when the text already
fails (a racer-tui check has run it anyway, as contained), unless it cannot compile or is
too long for DRoA to take at all.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from typing import Any

from sim.reward.droa_rules import SIZE, DroaReason, static_reasons
from sim.reward.probe import droa_runtime_reasons
from sim.reward.sandbox import DEFAULT_MEMORY_MB


@dataclass(frozen=True)
class DroaVerdict:
    track: str  # the route DRoA's run used
    reasons: tuple[DroaReason, ...]  # in DRoA's order: the first is the one it would say

    @property
    def accepted(self) -> bool:
        return not self.reasons

    def to_json(self) -> dict[str, Any]:
        return {
            "accepted": self.accepted,
            "track": self.track,
            "reasons": [reason.to_json() for reason in self.reasons],
        }


def droa_verdict(
    source: str, name: str, track: str, *, memory_mb: int = DEFAULT_MEMORY_MB
) -> DroaVerdict:
    """Would DeepRacer on AWS accept `source` for a model on `track`?"""
    reasons = static_reasons(source)
    if not any(reason.kind == SIZE for reason in reasons) and _compiles(source):
        reasons += droa_runtime_reasons(source, name, track, memory_mb=memory_mb)
    return DroaVerdict(track, tuple(reasons))


def _compiles(source: str) -> bool:
    try:
        ast.parse(source)
    except (SyntaxError, ValueError):
        return False
    return True

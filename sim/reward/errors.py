"""The error a racer's reward function raises in racer-tui's hands: one sentence naming the
file (and line) and what to do. Its own module, so the sandbox that contains the code and
the loader that calls it both say it the same way."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sim.foundation.remedies import RemedyError

FIX_ADVICE = "fix the function and try again"


class RewardFunctionError(RemedyError):
    """A reward function that cannot be loaded or run; `str()` is one sentence for the racer:
    where (`display`, `line`), what is wrong (`reason`) and what to do (`advice`)."""

    def __init__(
        self,
        path: Path | str,
        reason: str,
        line: int | None = None,
        advice: str = FIX_ADVICE,
    ) -> None:
        self.display = str(path)
        self.path = Path(path)
        self.reason = reason
        self.line = line
        self.advice = advice
        where = self.display if line is None else f"{self.display} line {line}"
        super().__init__(f"{where}: {reason}; {advice}.")

    def __reduce__(self) -> tuple[Any, ...]:
        # The training worker may hand the error across a process boundary.
        return (type(self), (self.display, self.reason, self.line, self.advice))

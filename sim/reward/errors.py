"""The error a racer's reward function raises in racer-tui's hands: one sentence naming the
file (and line) and what to do. Its own module, so the sandbox that contains the code and
the loader that calls it both say it the same way."""

from __future__ import annotations

from pathlib import Path
from typing import Any

FIX_ADVICE = "fix the function and try again"


class RewardFunctionError(Exception):
    """A reward function that cannot be loaded or run; `str()` is one sentence for the racer."""

    def __init__(
        self,
        path: Path | str,
        problem: str,
        line: int | None = None,
        advice: str = FIX_ADVICE,
    ) -> None:
        self.display = str(path)
        self.path = Path(path)
        self.problem = problem
        self.line = line
        self.advice = advice
        super().__init__(str(self))

    def __str__(self) -> str:
        where = self.display if self.line is None else f"{self.display} line {self.line}"
        return f"{where}: {self.problem}; {self.advice}."

    def __reduce__(self) -> tuple[Any, ...]:
        # The training worker may hand the error across a process boundary.
        return (type(self), (self.display, self.problem, self.line, self.advice))

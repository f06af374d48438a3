"""Issue 42, point 13: `racer-tui train` piped into another program printed nothing until
the end (a live view draws only its last frame when its output is not a terminal). Piped,
it prints a line per policy update, flushed as it goes."""

from __future__ import annotations

import io
from collections.abc import Iterator

import pytest
from rich.console import Console

from racer_tui.cli.train_commands import _show_live
from sim.training import events


class Pipe(io.StringIO):
    """What a program reading the output gets: only text written and flushed."""

    def __init__(self) -> None:
        super().__init__()
        self.delivered = ""

    def flush(self) -> None:
        self.delivered = self.getvalue()

    def isatty(self) -> bool:
        return False


def test_piped_training_output_arrives_line_by_line(monkeypatch: pytest.MonkeyPatch) -> None:
    pipe = Pipe()
    monkeypatch.setattr("sys.stdout", pipe)
    seen_mid_run: list[str] = []

    def run() -> Iterator[events.Event]:
        yield events.Started(0.0, "ada", "hairpin", ("vector",), 8, "scratch", 0, 5.0, 42)
        for iteration in (1, 2):
            yield events.Update(
                10.0 * iteration, iteration, 2048 * iteration, 30 * iteration, 1.5, 0.0,
                0.4, 0.0, 0.1, 5000.0, 30, 10.0, 40.0, 0, None,
            )  # fmt: skip
            seen_mid_run.append(pipe.delivered)  # the reader's view before the next event
        yield events.Ended(20.0, "finished", "the time limit was reached", 4096, 60, 40.0, None)

    assert not Console(stderr=False).is_terminal
    ended = _show_live(run(), "ada", None)  # type: ignore[arg-type]
    assert ended.kind == "finished"
    assert "iteration 1" in seen_mid_run[0] and "iteration 2" not in seen_mid_run[0]
    assert "iteration 2" in seen_mid_run[1]
    assert "finished: the time limit was reached" in pipe.getvalue()

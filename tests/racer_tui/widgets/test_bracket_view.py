"""The bracket as the Nights screen and the projector draw it: a column per round, named as
racers name rounds, the deciding race only once it is needed."""

from __future__ import annotations

import io

from rich.console import Console

from league.bracket_records import NightBracket
from league.brackets import Format, draw_bracket
from racer_tui.app.widgets.bracket_view import bracket_view
from sim.race.rules import HEAD_TO_HEAD_RULES


def drawn(seeds: int, form: Format) -> NightBracket:
    ids = [f"e{k}" for k in range(1, seeds + 1)]
    return NightBracket(
        id="b",
        night_id="n",
        bracket=draw_bracket(ids, form),
        rules=HEAD_TO_HEAD_RULES,
        created_at="2026-11-30T12:00:00Z",
        racers={entrant: f"racer {entrant}" for entrant in ids},
    )


def shown(bracket: NightBracket, width: int = 100, name: str = "R") -> str:
    console = Console(width=width, record=True, file=io.StringIO())
    console.print(bracket_view(bracket, {e: f"{name}{e[1:]}" for e in bracket.bracket.seeds}))
    return console.export_text()


def test_a_single_elimination_of_six_names_its_rounds_and_byes() -> None:
    text = shown(drawn(6, Format.SINGLE))
    assert "Quarter-finals" in text and "Semi-finals" in text and "Final" in text
    assert text.count("bye") == 2  # six in a bracket of eight: the top two seeds go through
    assert "to be decided" in text and "Champion" not in text
    assert text.index("R1") < text.index("R2")  # the first seed heads the first column


def test_a_double_elimination_draws_its_losers_rounds_and_no_decider_yet() -> None:
    text = shown(drawn(4, Format.DOUBLE))
    assert "Winners' round 1" in text and "Losers' round 1" in text
    assert "Grand final" in text and "Deciding race" not in text


def test_long_names_at_60_columns_end_in_an_ellipsis_and_never_wrap() -> None:
    text = shown(drawn(8, Format.SINGLE), width=56, name="a racer with a very long name ")
    lines = [line for line in text.splitlines() if line.strip()]
    # A header and its rule, then four matches of two sides: one line each.
    assert sum("a racer" in line for line in lines) == 8 and len(lines) == 2 + 8
    assert "…" in text and all(len(line) <= 56 for line in lines)

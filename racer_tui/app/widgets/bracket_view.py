"""A night's knock-out bracket drawn as a table, one column per round (league.brackets).

Each match is two lines, its racers: the winner bold with a tick, the loser dim; a side not
known yet says so, a bye says "bye". The match to race next stands out. A double
elimination draws its winners' rounds and finals, then its losers' rounds under them, so
each table keeps a column room enough for a name at 80 columns. The Nights screen and the
night's projector both draw it from the same `NightBracket`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from rich import box
from rich.console import Group, RenderableType
from rich.table import Table
from rich.text import Text

from league.bracket_records import NightBracket
from league.brackets import BYE, Format, Match

NEXT_STYLE = "bold black on yellow"
# Winners' rounds from the last one back, in a single elimination.
ROUNDS_FROM_THE_END = ("Final", "Semi-finals", "Quarter-finals")


def round_title(match: Match, rounds: int, form: Format) -> str:
    """What a round is called: "Semi-finals" in a single elimination, "Losers' round 2"."""
    if match.bracket == "final":
        return "Grand final" if match.id == "GF" else "Deciding race"
    if match.bracket == "losers":
        return f"Losers' round {match.round}"
    if form is Format.DOUBLE:
        return f"Winners' round {match.round}"
    from_the_end = rounds - match.round
    if from_the_end < len(ROUNDS_FROM_THE_END):
        return ROUNDS_FROM_THE_END[from_the_end]
    return f"Round {match.round}"


def bracket_view(drawn: NightBracket, names: Mapping[str, str]) -> RenderableType:
    """The bracket as it stands; `names` are entrant ids' display names."""
    winners = drawn.winners
    upcoming = drawn.next_match()
    matches = drawn.bracket.matches
    rounds = max((m.round for m in matches if m.bracket == "winners"), default=1)
    top = [m for m in matches if m.bracket != "losers" and _shown(drawn, m)]
    losers = [m for m in matches if m.bracket == "losers"]

    def cell(match: Match) -> Text:
        a, b = drawn.sides(match)
        winner = winners.get(match.id)
        lines = Text()
        for number, side in enumerate((a, b)):
            if number:
                lines.append("\n")
            lines.append_text(_side(side, winner, names))
        if upcoming is not None and match.id == upcoming.id:
            lines.stylize(NEXT_STYLE)
        return lines

    parts: list[RenderableType] = [_table(top, drawn.bracket.format, rounds, cell)]
    if losers:
        parts.append(_table(losers, drawn.bracket.format, rounds, cell))
    champion = drawn.bracket.champion(winners)
    if champion:
        parts.append(Text(f"Champion: {names.get(champion, champion)}", style="bold green"))
    return Group(*parts)


def _shown(drawn: NightBracket, match: Match) -> bool:
    """The deciding race is drawn only once it is needed (or raced)."""
    if match.id != "GF2":
        return True
    return match in drawn.bracket.ready(drawn.winners) or match.id in drawn.winners


def _side(side: str | None, winner: str | None, names: Mapping[str, str]) -> Text:
    if side is None:
        return Text("to be decided", style="dim")
    if side == BYE:
        return Text("bye", style="dim")
    name = names.get(side, side)
    if winner is None:
        return Text(name)
    return Text(f"✓ {name}", style="bold") if side == winner else Text(name, style="dim")


def _table(
    matches: Sequence[Match], form: Format, rounds: int, cell: Callable[[Match], Text]
) -> Table:
    columns: dict[str, list[Match]] = {}
    for match in matches:
        columns.setdefault(round_title(match, rounds, form), []).append(match)
    table = Table(box=box.SIMPLE_HEAD, expand=True, padding=(0, 1), show_edge=False)
    for title in columns:
        table.add_column(title, ratio=1, no_wrap=True, overflow="ellipsis")
    tallest = max(len(column) for column in columns.values())
    for row in range(tallest):
        cells: list[Text] = []
        for column in columns.values():
            cells.append(cell(column[row]) if row < len(column) else Text(""))
        table.add_row(*cells)
        if row < tallest - 1:
            table.add_row()
    return table

"""A night's knock-out bracket drawn as a table, one column per round, named as
league.bracket_rounds names them for every screen.

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
from league.bracket_rounds import BracketRound, bracket_rounds
from league.brackets import BYE, Match

NEXT_STYLE = "bold black on yellow"


def bracket_view(drawn: NightBracket, names: Mapping[str, str]) -> RenderableType:
    """The bracket as it stands; `names` are entrant ids' display names."""
    winners = drawn.winners
    upcoming = drawn.next_match()
    rounds = bracket_rounds(drawn)
    top = [one for one in rounds if one.part != "losers"]
    losers = [one for one in rounds if one.part == "losers"]

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

    parts: list[RenderableType] = [_table(top, cell)]
    if losers:
        parts.append(_table(losers, cell))
    champion = drawn.bracket.champion(winners)
    if champion:
        parts.append(Text(f"Champion: {names.get(champion, champion)}", style="bold green"))
    return Group(*parts)


def _side(side: str | None, winner: str | None, names: Mapping[str, str]) -> Text:
    if side is None:
        return Text("to be decided", style="dim")
    if side == BYE:
        return Text("bye", style="dim")
    name = names.get(side, side)
    if winner is None:
        return Text(name)
    return Text(f"✓ {name}", style="bold") if side == winner else Text(name, style="dim")


def _table(rounds: Sequence[BracketRound], cell: Callable[[Match], Text]) -> Table:
    table = Table(box=box.SIMPLE_HEAD, expand=True, padding=(0, 1), show_edge=False)
    for one in rounds:
        table.add_column(one.title, ratio=1, no_wrap=True, overflow="ellipsis")
    tallest = max(len(one.matches) for one in rounds)
    for row in range(tallest):
        cells: list[Text] = []
        for one in rounds:
            cells.append(cell(one.matches[row]) if row < len(one.matches) else Text(""))
        table.add_row(*cells)
        if row < tallest - 1:
            table.add_row()
    return table

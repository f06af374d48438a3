"""The command palette (ctrl+p): every action of every section, found by typing.

The commands are built from the same BINDINGS the footer and the help screen show (see
`RacerTuiApp.palette_commands`), so a new key is in the palette without another list to
keep up to date. Choosing a command in another section switches to that section first.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from textual.command import DiscoveryHit, Hit, Hits, Provider
from textual.screen import Screen


@dataclass(frozen=True)
class PaletteCommand:
    text: str  # "Garage: Clone"
    help: str
    run: Callable[[], Awaitable[None] | None]


@runtime_checkable
class HasPaletteCommands(Protocol):
    def palette_commands(self, screen: Screen[object]) -> list[PaletteCommand]: ...


class RacerCommands(Provider):
    """Lists the app's palette commands; fuzzy search over their text."""

    def _commands(self) -> list[PaletteCommand]:
        app = self.app
        if not isinstance(app, HasPaletteCommands):
            return []
        return app.palette_commands(self.screen)

    async def discover(self) -> Hits:
        for command in self._commands():
            yield DiscoveryHit(command.text, command.run, help=command.help)

    async def search(self, query: str) -> Hits:
        matcher = self.matcher(query)
        for command in self._commands():
            score = matcher.match(command.text)
            if score > 0:
                yield Hit(score, matcher.highlight(command.text), command.run, help=command.help)

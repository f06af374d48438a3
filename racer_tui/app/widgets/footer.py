"""The key footer of every screen: one line, drawn by one widget.

Textual's own footer (8.2.8) is a container that builds a widget per key, and builds them
all again each time the screen's bindings change: on every section switch, every dialog
opened and closed, every focus move that changes a key. Each key widget, with the two
style nodes Textual makes for its parts, is some forty objects in reference cycles that
live until the next change, long enough to reach the oldest generation: in the soak
benchmark they were most of what every full garbage collection had to free (about 250
nodes and 20,000 objects every two seconds of key presses), and the footer kept every key
it had ever shown besides (its `compact` watchers). This footer keeps the keys as data
and draws them as one line of text: a change of keys is a repaint, not a recompose.

What it shows is Textual's footer's: each shown binding of the screen once per action, in
the screen's order, disabled ones dim, and on the right the command palette's key when
there is room. Below `COMPACT_WIDTH` the padding goes, and so does the palette key (the
header shows it too). Keys that still do not fit are left out by priority rather than cut
at the edge: a screen's own keys in the order it declares them, and the help key always,
since the help screen (and the command palette) lists every key. Before any key is left
out, a screen's shorter labels (`FOOTER_SHORT_LABELS`, by action: "Close" for "Close
night") take the place of the long ones, so a narrow terminal keeps a busy screen's keys.
A click on a key presses it; hovering shows its tooltip.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from rich.cells import cell_len
from rich.color import Color as RichColor
from rich.style import Style
from rich.text import Text
from textual import events
from textual.color import Color
from textual.screen import Screen
from textual.widget import Widget

HELP_ACTION = "help"  # racer-tui's help key ("?") runs app.help
PALETTE_EDGE = "\u258f"  # the thin bar left of the palette key, as Textual draws it


@dataclass(frozen=True)
class ShownKey:
    """One key as the footer shows it."""

    key: str  # what pressing it simulates
    display: str  # as shown: "^r", "?"
    description: str
    action: str
    enabled: bool
    tooltip: str
    short: str = ""  # the label where the line is short of room ("": the description)


@dataclass(frozen=True)
class PlacedKey:
    """A key laid out on the line: it takes cells `start` to `end` (exclusive)."""

    key: ShownKey
    start: int
    end: int


def screen_keys(screen: Screen[Any]) -> tuple[tuple[ShownKey, ...], ShownKey | None]:
    """The keys `screen` shows in a footer, and the command palette's key (or None)."""
    app = screen.app
    palette_binding = app.COMMAND_PALETTE_BINDING if app.ENABLE_COMMAND_PALETTE else None
    keys: list[ShownKey] = []
    actions: set[str] = set()
    palette: ShownKey | None = None
    short_labels: dict[str, str] = getattr(screen, "FOOTER_SHORT_LABELS", {})
    for key, (_, binding, enabled, tooltip) in screen.active_bindings.items():
        shown = ShownKey(
            key=binding.key,
            display=app.get_key_display(binding),
            description=binding.description,
            action=binding.action,
            enabled=enabled,
            tooltip=tooltip or binding.tooltip,
            short=short_labels.get(binding.action, ""),
        )
        if key == palette_binding:
            palette = shown
        elif binding.show and binding.action not in actions:
            actions.add(binding.action)  # the first key bound to an action stands for all
            keys.append(shown)
    return tuple(keys), palette


def key_width(key: ShownKey, *, compact: bool) -> int:
    """Cells one key takes on the line: its key, its label and the space around them."""
    label = cell_len(key.description) + 1 if key.description else 0
    if compact:  # "k label" and one cell after it
        return cell_len(key.display) + label + 1
    return cell_len(key.display) + 2 + label  # " k label "


def fitting(keys: tuple[ShownKey, ...], room: int, *, compact: bool) -> list[ShownKey]:
    """The keys that fit in `room` cells, by priority (declared order, help always),
    with their short labels if that is what it takes to keep them all."""
    if sum(key_width(key, compact=compact) for key in keys) > room:
        keys = tuple(replace(key, description=key.short or key.description) for key in keys)
    helps = [key for key in keys if key.action.endswith(HELP_ACTION)]
    room -= sum(key_width(key, compact=compact) for key in helps)
    kept: list[ShownKey] = []
    for key in keys:
        if key in helps:
            continue
        width = key_width(key, compact=compact)
        if width > room:
            break  # the keys after it matter less: leave them for the help screen
        room -= width
        kept.append(key)
    return [key for key in keys if key in kept or key in helps]


def palette_width(key: ShownKey) -> int:
    """Cells the palette key takes: its edge, "^p palette" and a cell after it."""
    return cell_len(PALETTE_EDGE) + key_width(key, compact=True)


DIM = Style(dim=True)


@dataclass(frozen=True)
class ThemeStyles:
    """The footer's colours, from the theme's footer variables (as Textual's footer uses).

    Read from the theme at each paint rather than declared as component classes: Textual
    builds a style node per component class each time it restyles a widget, which it does
    to every widget of a screen on each section switch."""

    key: Style
    description: Style
    hover: Style  # added to a key under the mouse
    edge: Style  # the bar left of the palette key

    @classmethod
    def of(cls, footer: Widget) -> ThemeStyles:
        variables = footer.app.get_css_variables()
        background = footer.styles.background

        def colour(name: str, alpha: float = 1.0) -> RichColor:
            laid = background + Color.parse(variables[name]).multiply_alpha(alpha)
            return laid.rich_color

        return cls(
            key=Style(
                color=colour("footer-key-foreground"),
                bgcolor=colour("footer-key-background"),
                bold=True,
            ),
            description=Style(
                color=colour("footer-description-foreground"),
                bgcolor=colour("footer-description-background"),
            ),
            hover=Style(bgcolor=colour("block-hover-background")),
            edge=Style(color=colour("foreground", alpha=0.2)),
        )


class RacerFooter(Widget, can_focus=False):
    COMPACT_WIDTH = 110
    DEFAULT_CSS = """
    RacerFooter {
        dock: bottom;
        height: 1;
        width: 1fr;
        color: $footer-foreground;
        background: $footer-background;
    }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._keys: tuple[ShownKey, ...] = ()
        self._palette: ShownKey | None = None
        self._hovered: ShownKey | None = None

    def on_mount(self) -> None:
        self.screen.bindings_updated_signal.subscribe(self, self.bindings_changed)
        self.bindings_changed(self.screen)

    def on_unmount(self) -> None:
        self.screen.bindings_updated_signal.unsubscribe(self)

    def bindings_changed(self, screen: Screen[Any]) -> None:
        # A section switch says the bindings changed about six times over for the same
        # keys: repaint only when what the footer shows is different.
        keys, palette = screen_keys(screen)
        if (keys, palette) != (self._keys, self._palette):
            self._keys, self._palette = keys, palette
            self._hovered, self.tooltip = None, None  # the key under the mouse may be gone
            self.refresh()

    @property
    def shown_keys(self) -> tuple[ShownKey, ...]:
        """The keys this footer shows (at its width, the first that fit)."""
        return self._keys

    @property
    def shown_palette(self) -> ShownKey | None:
        return self._palette

    @property
    def compact(self) -> bool:
        return self.size.width < self.COMPACT_WIDTH

    def placed(self) -> list[PlacedKey]:
        """The keys on the line at the footer's width, where each one is drawn."""
        width = self.size.width
        compact = self.compact
        palette = None if compact else self._palette
        room = width - (palette_width(palette) if palette is not None else 0)
        placed: list[PlacedKey] = []
        start = 0
        for key in fitting(self._keys, room, compact=compact):
            end = start + key_width(key, compact=compact)
            placed.append(PlacedKey(key, start, end))
            start = end
        if palette is not None:
            placed.append(PlacedKey(palette, width - palette_width(palette), width))
        return placed

    def render(self) -> Text:
        line = Text(no_wrap=True, overflow="crop", end="")
        theme = ThemeStyles.of(self)
        compact = self.compact
        for place in self.placed():
            key = place.key
            line.append(" " * (place.start - line.cell_len))
            keys, labels = theme.key, theme.description
            if key == self._hovered:
                keys, labels = keys + theme.hover, labels + theme.hover
            if not key.enabled:
                keys, labels = keys + DIM, labels + DIM
            label = f" {key.description}" if key.description else ""
            if key == self._palette:
                line.append(PALETTE_EDGE, theme.edge)
                line.append(key.display, keys)
                line.append(label + " ", labels)
            elif compact:
                line.append(key.display, keys)
                line.append(label, labels)
                line.append(" ")
            else:
                line.append(f" {key.display} ", keys)
                if key.description:
                    line.append(f"{key.description} ", labels)
        return line

    def _key_at(self, x: int) -> ShownKey | None:
        for place in self.placed():
            if place.start <= x < place.end:
                return place.key
        return None

    def on_mouse_move(self, event: events.MouseMove) -> None:
        hovered = self._key_at(event.x)
        if hovered != self._hovered:
            self._hovered = hovered
            self.tooltip = hovered.tooltip if hovered is not None and hovered.tooltip else None
            self.refresh()

    def on_leave(self, event: events.Leave) -> None:
        if self._hovered is not None:
            self._hovered = None
            self.tooltip = None
            self.refresh()

    def on_mouse_down(self, event: events.MouseDown) -> None:
        key = self._key_at(event.x)
        if key is None:
            return
        if key.enabled:
            self.app.simulate_key(key.key)
        else:
            self.app.bell()

"""The key footer of every screen, compact when the terminal is narrow.

Textual's footer pads each key; at 80 columns that pushes half of a section's keys off
the line. Below `COMPACT_WIDTH` the padding goes, and so does the palette key (the header
shows it too). Keys that still do not fit are left out by priority rather than cut at the
edge: a screen's own keys in the order it declares them, and the help key always, since
the help screen (and the command palette) lists every key.

It also stops a leak in Textual's own footer (8.2.8): every time a screen's bindings
change the footer recomposes, and each new key is bound to the footer's `compact`
reactive with `data_bind`, which adds a watcher to the footer. Textual drops the watchers
of removed keys only when `compact` next changes, which at a fixed width is never: the
footer held every key it ever showed (about 1,700 objects per section switch, and full
garbage collections that grew to a second over a league night). `tests/racer_tui/
widgets/test_footer.py` keeps the minimal reproduction.
"""

from __future__ import annotations

from typing import Any

from textual import events
from textual.app import ComposeResult
from textual.screen import Screen
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

# Where Textual keeps the watchers `watch` and `data_bind` add to a reactable (a private
# attribute of `textual.reactive`, named the same since Textual 0.47).
_WATCHERS_ATTRIBUTE = "__watchers"
HELP_ACTION = "help"  # racer-tui's help key ("?") runs app.help


class RacerFooter(Footer):
    COMPACT_WIDTH = 110

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._last_shown: tuple[object, ...] | None = None
        self._laid_out_for = 0  # the width the keys were last fitted to

    def on_resize(self, event: events.Resize) -> None:
        compact = event.size.width < self.COMPACT_WIDTH
        self.compact = compact
        self.show_command_palette = not compact
        if event.size.width != self._laid_out_for and self.is_attached and self.children:
            # Which keys fit (and whether the palette key shows) depends on the width.
            self.call_after_refresh(self.recompose)
        self._laid_out_for = event.size.width

    def bindings_changed(self, screen: Screen[Any]) -> None:
        # Textual recomposes the footer every time the screen says its bindings changed,
        # which a section switch says about six times over for the same keys: rebuilding
        # and restyling a dozen keys each time was a third of a switch's work. Recompose
        # only when what the footer shows is different.
        shown = self._shown(screen)
        if shown == self._last_shown and self.children:
            return
        super().bindings_changed(screen)
        if screen.app.app_focus and self.is_attached and screen is self.screen:
            self._last_shown = shown  # Textual recomposes it (after the next refresh)

    @staticmethod
    def _shown(screen: Screen[Any]) -> tuple[object, ...]:
        """What the footer would show for `screen`: the width, and each key as displayed,
        its label, action, group, whether it is enabled and its tooltip."""
        keys = tuple(
            (
                binding.key,
                binding.key_display,
                binding.description,
                binding.action,
                binding.group,
                binding.show,
                enabled,
                tooltip,
            )
            for _, binding, enabled, tooltip in screen.active_bindings.values()
        )
        return (screen.app.size.width, *keys)  # which keys fit depends on the width

    def compose(self) -> ComposeResult:
        widgets = list(super().compose())
        keys = [widget for widget in widgets if isinstance(widget, FooterKey)]
        if len(keys) != len(widgets):  # binding groups: Textual lays those out itself
            yield from widgets
            return
        yield from self._fitting(keys, self.app.size.width)

    def _fitting(self, keys: list[FooterKey], width: int) -> list[FooterKey]:
        """The keys that fit in `width` cells, by priority (declared order, help first)."""
        palette = [key for key in keys if key.has_class("-command-palette")]
        room = width - sum(self._width(key) + 1 for key in palette)  # its border
        rest = [key for key in keys if key not in palette]
        helps = [key for key in rest if key.action.endswith(HELP_ACTION)]
        room -= sum(self._width(key) for key in helps)
        kept: list[FooterKey] = []
        for key in rest:
            if key in helps:
                continue
            if self._width(key) > room:
                break  # the keys after it matter less: leave them for the help screen
            room -= self._width(key)
            kept.append(key)
        shown = set(map(id, [*kept, *helps, *palette]))
        return [key for key in keys if id(key) in shown]

    def _width(self, key: FooterKey) -> int:
        """Cells one key takes: its key, its label and the space Textual's CSS gives it."""
        label = len(key.description)
        if self.compact:  # no padding, one cell of margin after
            return len(key.key_display) + (label + 1 if label else 0) + 1
        return len(key.key_display) + 2 + (label + 1 if label else 0)

    async def recompose(self) -> None:
        await super().recompose()
        self.forget_removed_keys()

    def forget_removed_keys(self) -> None:
        """Drop the watchers that removed keys left on this footer, the way Textual itself
        drops them when the watched value changes (watchers of closing nodes go)."""
        watchers: dict[str, list[tuple[object, object]]] = getattr(self, _WATCHERS_ATTRIBUTE, {})
        for entries in watchers.values():
            entries[:] = [
                (node, callback)
                for node, callback in entries
                if not getattr(node, "_closing", False)
            ]

"""The key footer of every screen, compact when the terminal is narrow.

Textual's footer pads each key; at 80 columns that pushes half of a section's keys off
the line. Below `COMPACT_WIDTH` the padding goes, and so does the palette key (the header
shows it too), so most keys stay in sight; every key is also in the help screen and the
command palette.

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
from textual.screen import Screen
from textual.widgets import Footer

# Where Textual keeps the watchers `watch` and `data_bind` add to a reactable (a private
# attribute of `textual.reactive`, named the same since Textual 0.47).
_WATCHERS_ATTRIBUTE = "__watchers"


class RacerFooter(Footer):
    COMPACT_WIDTH = 110

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._last_shown: tuple[object, ...] | None = None

    def on_resize(self, event: events.Resize) -> None:
        compact = event.size.width < self.COMPACT_WIDTH
        self.compact = compact
        if self.show_command_palette == compact:  # the palette key comes or goes
            self.show_command_palette = not compact
            if self.is_attached and self.children:
                self.call_after_refresh(self.recompose)

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
        """What the footer would show for `screen`: each key as displayed, its label,
        action, group, whether it is enabled and its tooltip (the palette key included)."""
        return tuple(
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

"""A click on a widget in the moment it is being removed must not crash the app.

Textual (8.2) starts a text selection on every mouse-down: it takes the widget the
compositor last drew under the pointer and reads its parent's region. Between a widget's
removal and the next layout the compositor still maps it, but its parent is already None,
and `Screen._forward_event` raises AttributeError: a click that lands as a dialog closes
or a list is rebuilt ended the app (the monkey found it after 10,744 actions). Such a
mouse-down is dropped here, on every screen (Textual's own too: the command palette); the
click it began hits nothing that is still there.
"""

from __future__ import annotations

from typing import Any

from textual import events
from textual.screen import Screen


def _lands_on_a_removed_widget(screen: Screen[Any], event: events.MouseDown) -> bool:
    widget, _ = screen.get_widget_and_offset_at(event.x, event.y)
    return widget is not None and not isinstance(widget, Screen) and widget.parent is None


def ignore_clicks_on_removed_widgets() -> None:
    """Wrap `Screen._forward_event` once per process (idempotent)."""
    forward = Screen._forward_event
    if getattr(forward, "ignores_removed_widgets", False):
        return

    def forward_event(self: Screen[Any], event: events.Event) -> None:
        if isinstance(event, events.MouseDown) and _lands_on_a_removed_widget(self, event):
            return
        forward(self, event)

    forward_event.ignores_removed_widgets = True  # type: ignore[attr-defined]
    Screen._forward_event = forward_event  # type: ignore[method-assign]

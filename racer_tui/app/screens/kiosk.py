"""Kiosk screens: the venue's big screen, where anyone in the room can reach the keyboard.

A kiosk answers only its own keys. Esc does nothing; leaving takes a deliberate key (q or
ctrl+q) and a confirmation; it never opens another screen: the app's own keys (sections,
help, the command palette, quit without asking) are taken from it. Started on its own
(`racer-tui night projector`), leaving quits the program; opened from a section (p on the
League or Nights screen), leaving goes back there.

Textual filters a key out of every namespace after one that consumes it
(`check_consume_key`, as an Input keeps its letters from the app's bindings), priority
bindings included: a kiosk consumes every key, so only its own bindings are left.
"""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.widgets import Button, Label, Static

from racer_tui.app.screens.base import RacerModal, RacerScreen

LEAVE_HINT = "q leaves (it asks first)"


class LeaveKiosk(RacerModal[bool]):
    """Leave the venue's screen? y or Enter leaves, n or Esc stays. Like its kiosk, it
    answers only its own keys."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("y", "answer(True)", "Leave"),
        Binding("n,escape", "answer(False)", "Stay"),
    ]

    def __init__(self, what: str, then: str) -> None:
        super().__init__()
        self.what = what
        self.then = then

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(f"Leave the {self.what}?"), classes="dialog-title")
            yield Static(Text(self.then), classes="dialog-body")
            with Horizontal(classes="dialog-buttons"):
                # As every confirmation: staying on the left, the deliberate act right.
                yield Button("Stay (n)", id="stay", variant="primary")
                yield Button("Leave (y)", id="leave", variant="error")

    def on_mount(self) -> None:
        self.query_one("#stay", Button).focus()  # a stray Enter stays

    def check_consume_key(self, key: str, character: str | None) -> bool:
        return True

    def action_answer(self, leave: bool) -> None:
        self.dismiss(leave)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "leave")


class KioskScreen(RacerScreen[None]):
    """A screen for the venue: only its own keys; q or ctrl+q asks, then leaves."""

    KIOSK_BINDINGS: ClassVar[list[BindingType]] = [
        Binding("q,ctrl+q", "leave", "Leave", show=False),
        Binding("escape", "stay", "", show=False),  # a key anyone may press: nothing
    ]
    what: ClassVar[str] = "projector"
    # The host's notes (a training finished, a sync failed) are not the room's: they stay
    # off the venue's screen (the host walk saw one cover the projector's heading).
    # (Textual shows its toast rack from code, so its toasts are what the CSS hides.)
    DEFAULT_CSS = """
    KioskScreen Toast { visibility: hidden; }
    """

    def check_consume_key(self, key: str, character: str | None) -> bool:
        return True  # the app's keys do not reach past the kiosk

    @property
    def started_alone(self) -> bool:
        """Opened by `racer-tui night projector`: the program is the kiosk."""
        return getattr(self.app, "projector_night", None) is not None

    def action_stay(self) -> None:
        """Esc on the venue's screen: nothing happens."""

    def action_leave(self) -> None:
        then = (
            "racer-tui closes; the standings stay in the league."
            if self.started_alone
            else "The screen you opened it from comes back."
        )
        self.app.push_screen(LeaveKiosk(self.what, then), self._leave_answered)

    def _leave_answered(self, leave: bool | None) -> None:
        if not leave:
            return
        if self.started_alone:
            self.app.exit()
        else:
            self.dismiss(None)


def kiosk_bindings(*own: BindingType) -> list[BindingType]:
    """A kiosk screen's bindings: its own, then leaving and the inert Esc."""
    return [*own, *KioskScreen.KIOSK_BINDINGS]

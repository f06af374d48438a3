"""The one-line header of every section: the app's name, the sections as tabs (the current
one highlighted, each clickable) and the two keys a newcomer needs (help and commands)."""

from __future__ import annotations

from textual import events
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.widgets import Static

from racer_tui.app.sections import SECTIONS


class SectionTab(Static):
    """One section's tab; a click switches to it."""

    def __init__(self, mode: str, label: str, *, current: bool) -> None:
        super().__init__(label, classes="-current" if current else "")
        self.mode = mode

    async def on_click(self, event: events.Click) -> None:
        event.stop()
        await self.run_action(f"app.switch_section({self.mode!r})")


class HelpHint(Static):
    async def on_click(self, event: events.Click) -> None:
        event.stop()
        await self.run_action("app.help")


class SectionHeader(Horizontal):
    """`current` is the mode of the section on screen (None on screens outside sections)."""

    DEFAULT_CSS = """
    SectionHeader {
        height: 1;
        background: $panel;
        color: $text-muted;
    }
    SectionHeader > #brand { width: auto; padding: 0 1; color: $accent; text-style: bold; }
    SectionHeader > SectionTab { width: auto; padding: 0 1; }
    SectionHeader > SectionTab:hover { background: $boost; color: $text; }
    SectionHeader > SectionTab.-current {
        background: $accent;
        color: $text;
        text-style: bold;
    }
    SectionHeader > #context { width: 1fr; padding: 0 1; content-align: right middle; }
    SectionHeader > HelpHint { width: auto; padding: 0 1; }
    SectionHeader > HelpHint:hover { background: $boost; color: $text; }
    SectionHeader.-narrow > #context { display: none; }
    SectionHeader.-tiny > #brand { display: none; }
    """
    # Below this width the tabs and the full hint do not fit on one line (80 columns is the
    # classic terminal): the context note goes and the hint keeps just its two keys.
    NARROW_WIDTH = 100
    # Below this the app's name goes too, so every tab reads whole ("5 League", not "5 Leagu").
    TINY_WIDTH = 70
    HINT = "? help  ^p commands"
    SHORT_HINT = "? ^p"

    def __init__(self, current: str | None, context: str = "") -> None:
        super().__init__()
        self.current = current
        self._note_text = context

    def compose(self) -> ComposeResult:
        yield Static("racer-tui", id="brand")
        for section in SECTIONS:
            yield SectionTab(
                section.mode,
                f"{section.key} {section.title}",
                current=section.mode == self.current,
            )
        yield Static(self._note_text, id="context")
        yield HelpHint(self.HINT)

    def on_resize(self, event: events.Resize) -> None:
        narrow = event.size.width < self.NARROW_WIDTH
        self.set_class(narrow, "-narrow")
        self.set_class(event.size.width < self.TINY_WIDTH, "-tiny")
        self.query_one(HelpHint).update(self.SHORT_HINT if narrow else self.HINT)

    def set_context(self, text: str) -> None:
        """A short note at the right of the header, for example "3 models"."""
        self._note_text = text
        if self.is_mounted:
            self.query_one("#context", Static).update(text)

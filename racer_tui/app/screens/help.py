"""Every key of every screen, read from the screens' own BINDINGS so it cannot drift.

`binding_topics` walks the classes it is given (the app, each screen, the dialogs) and
collects the bindings they and their racer-tui base classes declare; a binding with no
description is an internal one and is left out. Keys that run the same action share a row.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.dom import DOMNode
from textual.widgets import Input, Static

from racer_tui.app.screens.base import RacerScreen
from racer_tui.app.widgets.footer import RacerFooter


@dataclass(frozen=True)
class KeyRow:
    keys: tuple[str, ...]  # as the footer shows them: "^s", "f2", "?"
    description: str
    tooltip: str = ""


@dataclass(frozen=True)
class HelpTopic:
    title: str
    rows: tuple[KeyRow, ...]


def declared_bindings(cls: type[DOMNode]) -> list[Binding]:
    """`cls`'s own BINDINGS and those of its racer-tui base classes (most derived first)."""
    found: list[Binding] = []
    for klass in cls.__mro__:
        if klass is not cls and not klass.__module__.startswith("racer_tui"):
            continue
        declared: list[BindingType] = list(klass.__dict__.get("BINDINGS", []))
        found.extend(Binding.make_bindings(declared))
    return found


def key_rows(
    bindings: Iterable[Binding], key_display: Callable[[Binding], str]
) -> tuple[KeyRow, ...]:
    """One row per described action, its keys in the order declared."""
    rows: dict[str, tuple[list[str], str, str]] = {}
    for binding in bindings:
        if not binding.description or binding.system:
            continue
        keys, _, _ = rows.setdefault(
            binding.action, ([], binding.description, binding.tooltip or "")
        )
        shown = key_display(binding)
        if shown not in keys:
            keys.append(shown)
    return tuple(
        KeyRow(tuple(keys), description, tooltip) for keys, description, tooltip in rows.values()
    )


def binding_topics(
    classes: Sequence[tuple[str, type[DOMNode]]],
    key_display: Callable[[Binding], str],
    extra: Sequence[tuple[str, Binding]] = (),
) -> list[HelpTopic]:
    """A topic per (title, class); `extra` adds bindings made at run time (the palette key)
    to the topic of that title."""
    topics: list[HelpTopic] = []
    for title, cls in classes:
        bindings = declared_bindings(cls) + [b for t, b in extra if t == title]
        rows = key_rows(bindings, key_display)
        if rows:
            topics.append(HelpTopic(title, rows))
    return topics


def topic_table(topic: HelpTopic, words: Sequence[str]) -> Table | None:
    """The topic as a two-column table, keeping rows that contain every word (None if none)."""
    table = Table.grid(padding=(0, 2))
    table.add_column(style="bold", no_wrap=True, min_width=10)
    table.add_column()
    shown = 0
    for row in topic.rows:
        keys = ", ".join(row.keys)
        haystack = f"{topic.title} {keys} {row.description} {row.tooltip}".casefold()
        if not all(word in haystack for word in words):
            continue
        what = Text(row.description)
        if row.tooltip:
            what.append(f"  {row.tooltip}", style="dim")
        table.add_row(Text(keys), what)
        shown += 1
    return table if shown else None


class HelpScreen(RacerScreen[None]):
    """The key reference; typing filters it."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "close", "Close help"),
        # The filter has the focus, and keys it does not use scroll the topics: a host
        # who presses PageDown in help expects the page to move, not to Tab there first.
        # (No descriptions: what they do goes without saying.)
        Binding("pagedown", "scroll('page_down')", show=False),
        Binding("pageup", "scroll('page_up')", show=False),
        Binding("down", "scroll('scroll_down')", show=False),
        Binding("up", "scroll('scroll_up')", show=False),
    ]

    def __init__(self, topics: Sequence[HelpTopic], notes: str = "") -> None:
        super().__init__()
        self.topics = list(topics)
        self.notes = notes

    def compose(self) -> ComposeResult:
        yield Static(Text("Help: every key, by screen", style="bold"), id="help-title")
        yield Input(placeholder="type to filter, Esc closes", id="help-filter")
        with VerticalScroll(id="help-topics"):
            for index, topic in enumerate(self.topics):
                yield Static(Text(topic.title), classes="help-topic-title", id=f"topic-{index}")
                yield Static(classes="help-topic", id=f"topic-{index}-keys")
            yield Static(Text(self.notes), id="help-notes")
        yield RacerFooter()

    def on_mount(self) -> None:
        self._filter("")

    def reset(self) -> None:
        """Unfiltered, at the top, ready for typing: as it opens again (the app keeps one
        help screen). Not on every resume: coming back from the palette over the help
        keeps what was typed."""
        if not self.is_mounted:
            return  # composing now: it starts that way
        search = self.query_one("#help-filter", Input)
        if search.value:
            with search.prevent(Input.Changed):
                search.value = ""
            self._filter("")
        self.query_one("#help-topics", VerticalScroll).scroll_home(animate=False)
        search.focus()

    @on(Input.Changed, "#help-filter")
    def _filter_changed(self, event: Input.Changed) -> None:
        self._filter(event.value)

    def _filter(self, text: str) -> None:
        words = text.casefold().split()
        for index, topic in enumerate(self.topics):
            table = topic_table(topic, words)
            self.query_one(f"#topic-{index}", Static).display = table is not None
            keys = self.query_one(f"#topic-{index}-keys", Static)
            keys.display = table is not None
            if table is not None:
                keys.update(table)

    def action_scroll(self, how: str) -> None:
        topics = self.query_one("#help-topics", VerticalScroll)
        getattr(topics, f"action_{how}")()

    def action_close(self) -> None:
        self.dismiss(None)

"""Workarounds for Textual bugs the app's users can reach, applied once for the whole app.

Each one names the bug, the Textual version it was seen in, and how to tell it is no longer
needed (its test in tests/racer_tui/test_key_bursts.py then fails to reproduce the fault
with the workaround taken out).
"""

from __future__ import annotations

import inspect
from collections.abc import Iterable
from typing import Any

from textual import events, work
from textual._ansi_sequences import ANSI_SEQUENCES_KEYS
from textual._xterm_parser import XTermParser
from textual.await_complete import AwaitComplete
from textual.command import CommandPalette
from textual.css.query import NoMatches
from textual.message import Message
from textual.screen import Screen
from textual.widgets import DataTable, OptionList

PATCHED = "_racer_tui_workaround"  # marks a patched method, so no patch is applied twice
LEAVING = "_racer_tui_leaving"  # a screen whose dismissal waits for the screens above it


def apply_workarounds() -> None:
    """Patch what must be patched; idempotent (every app built in a test calls it)."""
    if not getattr(OptionList._move_page, PATCHED, False):
        _page_keys_wait_for_lines()
    if not getattr(Screen.dismiss, PATCHED, False):
        _a_screen_is_dismissed_once()
    if not getattr(DataTable._on_click, PATCHED, False):
        _clicks_on_a_table_without_columns()
    if not getattr(CommandPalette._gather_commands, PATCHED, False):
        _a_closed_palette_stops_searching()
    if not getattr(XTermParser._sequence_to_key_events, PATCHED, False):
        _escape_and_a_key_in_one_read_are_two_keys()
    if not getattr(XTermParser.feed, PATCHED, False):
        _an_escape_before_a_typed_key_is_a_key()


def _page_keys_wait_for_lines() -> None:
    """Textual 8.2.8: `OptionList._move_page` reads the line of the highlighted option
    (`_index_to_line[highlighted]`) and the list's `_lines`, which are only built once the
    list has a size. A PageUp/PageDown that reaches a list before its first layout (the
    command palette or a Select's overlay opened by the key just before it, in the same
    burst of keys from the terminal) raised `KeyError: 0` and crashed the app (issue 42;
    others hit it too, e.g. kagan-sh/kagan-legacy#31). Until the list has its lines, a page
    key moves to the first or last option instead, which is where a page from the top
    ends in a short list anyway."""
    original = OptionList._move_page

    def move_page(self: OptionList, direction: int) -> None:
        highlighted = self.highlighted or 0
        if self._options and highlighted not in self._index_to_line:
            # `_index_to_line` builds the lines it can; still none: not laid out yet.
            if direction < 0:
                self.action_first()
            else:
                self.action_last()
            return
        original(self, direction)  # type: ignore[arg-type]

    setattr(move_page, PATCHED, True)
    OptionList._move_page = move_page  # type: ignore[method-assign]


def _a_screen_is_dismissed_once() -> None:
    """Textual 8.2.8: `Screen.dismiss` pops whatever screen is on top and calls the result
    callback, whether or not the screen dismissed is the one on top, or still there at all.
    Two ways out of one dialog queued together (Enter, whose Submitted or OptionSelected
    message is handled later, then Esc) dismissed it twice: the second took the screen
    below with it, or raised ScreenStackError when that was a section's own screen (the
    command palette, found by the monkey in issue 42). And a screen that closes itself
    while a dialog of its own is open over it (the editor's save finishing while "Discard
    your changes?" is asked) popped that dialog instead and stayed, its result already
    given: closing it later raised InvalidStateError. So: a screen no longer on the stack,
    or already on its way out, is not dismissed again; one under others first closes them
    (they answer None, as if cancelled), then itself."""
    original = Screen.dismiss

    def dismiss(self: Screen[Any], result: Any = None) -> AwaitComplete:
        stack = self.app.screen_stack
        if self not in stack or getattr(self, LEAVING, False):
            gone: AwaitComplete = AwaitComplete.nothing()  # type: ignore[no-untyped-call]
            return gone
        if stack[-1] is not self:
            setattr(self, LEAVING, True)
            self.pop_until_active()  # queued: the screens above close first

            def close() -> None:
                setattr(self, LEAVING, False)
                if self in self.app.screen_stack:
                    dismiss(self, result)

            self.app.call_later(close)
            later: AwaitComplete = AwaitComplete.nothing()  # type: ignore[no-untyped-call]
            return later
        return original(self, result)

    setattr(dismiss, PATCHED, True)
    Screen.dismiss = dismiss  # type: ignore[method-assign]


def _clicks_on_a_table_without_columns() -> None:
    """Textual 8.2.8: a click on a DataTable's header reads the column under it by index
    (`ordered_columns[column]`) without checking there is one; a table with no columns yet
    (a night with no heats, a board being refilled) draws its header row all the same, and
    a click there raised IndexError (found by the monkey on the Nights screen, issue 42).
    A click on a header or row label that is not there does nothing."""
    original = DataTable._on_click

    async def on_click(self: DataTable[Any], event: events.Click) -> None:
        meta = event.style.meta
        row, column = meta.get("row"), meta.get("column")
        if isinstance(row, int) and isinstance(column, int):
            if row == -1 and self.show_header and not 0 <= column < len(self.ordered_columns):
                return
            if column == -1 and self.show_row_labels and not 0 <= row < len(self.ordered_rows):
                return
        await original(self, event)

    setattr(on_click, PATCHED, True)
    DataTable._on_click = on_click  # type: ignore[method-assign]


def _a_closed_palette_stops_searching() -> None:
    """Textual 8.2.8: the command palette searches in a worker that looks up its result
    list when it starts; a palette closed before that (ctrl+p and Esc in one burst, or a
    palette typed into while it closes) has no list any more, and the worker's NoMatches
    stopped the app (found by the monkey, issue 42). A search whose palette has closed
    ends quietly; in an open palette it still fails as before."""
    search = inspect.unwrap(CommandPalette._gather_commands)  # the method under its @work

    async def gather_commands(self: CommandPalette, search_value: str) -> None:
        try:
            await search(self, search_value)
        except NoMatches:
            if self.is_attached and self in self.app.screen_stack:
                raise
            # Closed while it searched: there is nothing to show the commands in.

    setattr(gather_commands, PATCHED, True)
    patched = work(exclusive=True, group=CommandPalette._GATHER_COMMANDS_GROUP)(gather_commands)
    setattr(patched, PATCHED, True)
    CommandPalette._gather_commands = patched  # type: ignore[method-assign]


def _escape_and_a_key_in_one_read_are_two_keys() -> None:
    """Textual 8.2.8: Esc and a key that arrive in one read from the terminal (typed
    quickly, or over a slow link) are read as Alt and that key, as terminals send Alt+key.
    For a character with a name (`?`, space, `5`) the Alt is then dropped, and with it the
    Esc: a host's Esc then `?` did not close the dialog, and `?` went to it (issue 42's
    walk); a letter became `alt+q`, which nothing binds; a digit became a character of
    macOS's Option row (`\x1b5` is "∞" for WezTerm). racer-tui binds no Alt key, so
    such a pair is what was typed: Esc, then the key. (Alt and a named key, as an arrow,
    come as a sequence of their own and are left as they are.) No longer needed when
    `XTermParser().feed("\x1b?")` and a tick after the escape delay give two keys."""
    original = XTermParser._sequence_to_key_events

    def sequence_to_key_events(
        self: XTermParser, sequence: str, alt: bool = False
    ) -> Iterable[events.Key]:
        if alt and len(sequence) == 1 and sequence.isprintable():
            yield events.Key("escape", "\x1b")
            yield from original(self, sequence)
            return
        if len(sequence) == 2 and isinstance(ANSI_SEQUENCES_KEYS.get(sequence), str):
            # Esc and a digit, `-` or `=`: read whole as WezTerm's Option key of macOS
            # ("\x1b5" as "∞"), so a host's Esc then 5 typed quickly went nowhere.
            yield events.Key("escape", "\x1b")
            yield from original(self, sequence[1])
            return
        yield from original(self, sequence, alt)

    setattr(sequence_to_key_events, PATCHED, True)
    XTermParser._sequence_to_key_events = sequence_to_key_events  # type: ignore[method-assign]


# What an escape sequence's second character can be (CSI, SS3, OSC, DCS, APC, PM, ST, and
# Esc itself): an Esc before any of these may begin a sequence, and is left to the parser.
SEQUENCE_STARTS = frozenset("[O]P_^\\\x1b")


def _an_escape_before_a_typed_key_is_a_key() -> None:
    """Textual 8.2.8: an Esc with a typed character after it and another Esc after that, in
    one read (a host's Esc, `?`, Esc typed quickly), was read as an unknown sequence and
    given back with the Esc as `^`: the Esc was lost and `^` typed (issue 42's walk saw
    `^?`). A read is split after such an Esc, and the Esc timed out there, as if the rest
    had come a moment later: the Esc is a key of its own. The pairs Textual knows as keys
    (`\x1bb` and `\x1bf`, Option+arrows on macOS) are left whole. No longer needed when
    `XTermParser().feed("\x1b?\x1b")` gives Esc, `?` and (after a tick) Esc."""
    original = XTermParser.feed

    def feed(self: XTermParser, data: str) -> Iterable[Message]:
        start = 0
        for index in range(len(data) - 1):
            if data[index] == "\x1b" and _typed_after_escape(data[index : index + 2]):
                yield from original(self, data[start : index + 1])
                self._timeout_time = 0.0  # the Esc's wait for more is over: a key
                yield from self.tick()
                start = index + 1
        if start < len(data) or not data:
            yield from original(self, data[start:])

    setattr(feed, PATCHED, True)
    XTermParser.feed = feed  # type: ignore[method-assign]


def _typed_after_escape(pair: str) -> bool:
    """`pair` is Esc and a typed character that begins no sequence Textual knows as a key."""
    second = pair[1]
    if not second.isprintable() or second in SEQUENCE_STARTS:
        return False
    known = ANSI_SEQUENCES_KEYS.get(pair)
    return known is None or isinstance(known, str)

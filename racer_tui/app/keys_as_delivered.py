"""Keys and pastes delivered as a terminal delivers them, for tests and the monkey.

`Pilot.press` waits for the app to be idle after every key, so a test typing `5` after the
`t` that opens a dialog only ever types into a dialog that is ready. A terminal does not
wait: keys typed quickly arrive in one read and are all queued before the app handles the
first one (issue 42: the editor crashed and the Train dialog lost keys only then). `burst`
queues keys that way; `paste` queues a bracketed paste; `drain` waits (on the app's queues,
not on a clock) until everything queued has been handled.
"""

from __future__ import annotations

import asyncio
import unicodedata
from collections.abc import Callable, Iterable
from typing import Any

from textual import events
from textual._xterm_parser import XTermParser
from textual.app import App
from textual.keys import REPLACED_KEYS, _character_to_key, _get_unicode_name_from_key
from textual.pilot import Pilot

MAX_DRAIN_ROUNDS = 200  # a burst of a few hundred keys settles in a few rounds
INPUT_POLL_SECONDS = 0.005
INPUT_WAIT_SECONDS = 30.0  # far beyond the app's own limit for a key in flight


def key_event(key: str) -> events.Key:
    """The Key event a terminal driver would post for `key` (as Pilot builds it)."""
    if len(key) == 1 and not key.isalnum():
        key = _character_to_key(key)
    original = REPLACED_KEYS.get(key, key)
    character: str | None
    try:
        character = unicodedata.lookup(_get_unicode_name_from_key(original))
    except KeyError:
        character = key if len(key) == 1 else None
    return events.Key(key, character)


def _deliver(app: App[Any], event: events.Event) -> None:
    event.set_sender(app)
    driver = app._driver
    assert driver is not None, "the app is not running"
    driver.send_message(event)


def burst(app: App[Any], keys: Iterable[str]) -> None:
    """Queue every key at once, without letting the app handle any in between."""
    for key in keys:
        _deliver(app, key_event(key))


def typed(app: App[Any], text: str) -> None:
    """Queue `text` as typed on a terminal: read by Textual's own terminal parser, so each
    character becomes the Key event a terminal driver posts for it (U+202E included, which
    arrives as key `right_to_left_override` with the character itself). An Esc that could
    begin a sequence is read as the parser reads it once the terminal's escape delay passes
    with nothing more (the delay is not waited: it is over at once)."""
    parser = XTermParser()
    read = list(parser.feed(text))
    if parser._timeout_time is not None:  # an Esc waits for what may follow: nothing does
        parser._timeout_time = 0.0
        read += parser.tick()
    for event in read:
        if isinstance(event, events.Key):
            _deliver(app, event)


def paste(app: App[Any], text: str) -> None:
    """Queue a bracketed paste of `text`, as a terminal sends it."""
    _deliver(app, events.Paste(text))


def _queues_empty(app: App[Any]) -> bool:
    nodes: list[Any] = [app, *app.screen_stack]
    focused = app.focused
    if focused is not None:
        nodes.append(focused)
    return all(node._message_queue.empty() for node in nodes)


async def _until(settled: Callable[[], bool]) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + INPUT_WAIT_SECONDS
    while not settled() and loop.time() < deadline:
        await asyncio.sleep(INPUT_POLL_SECONDS)


async def drain(pilot: Pilot[Any]) -> None:
    """Wait until the app has handled what was queued (and what that queued in turn).

    Event-driven: each round waits until every node of the screen has handled what was in
    its queue when the round began (Pilot's `_wait_for_screen`). `Pilot.pause` also waits
    for the process to be idle, which a screen that animates (a race, the welcome demo)
    never is: it then waits its whole second."""
    app = pilot.app
    quiet_rounds = 0
    for _ in range(MAX_DRAIN_ROUNDS):
        if not app.is_running:
            return
        await pilot._wait_for_screen()
        await asyncio.sleep(0)
        input_settled = getattr(app, "input_settled", None)
        if input_settled is not None and not input_settled():
            # a key's binding is still running (a section being composed): its next keys
            # wait for it, so this waits too (on a short poll: an action can take seconds)
            quiet_rounds = 0
            await _until(input_settled)
            continue
        settled = _queues_empty(app)
        quiet_rounds = quiet_rounds + 1 if settled else 0
        if quiet_rounds >= 2:  # twice: a handler may post once more after the queue emptied
            return

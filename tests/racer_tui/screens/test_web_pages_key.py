"""The league's web pages from the app (b on the Nights screen): a real `racer-tui serve`
child, its address on the screen, stopped by b again and with the app."""

from __future__ import annotations

import asyncio
import urllib.request
from typing import Any

import psutil
from textual.pilot import Pilot
from textual.widgets import Static

from league.nights import new_night
from league.opening import open_league
from racer_tui.app.application import create_app
from racer_tui.app.screens.nights import NightsScreen
from sim.foundation.home import data_home
from sim.tracks.catalog import resolve_track
from tests.racer_tui.screens.test_nights import the_nights_screen
from tests.racer_tui.screens.tui_helpers import Notifications, settle


async def _until(pilot: Pilot[Any], done: Any, seconds: float = 30.0) -> None:
    for _ in range(int(seconds / 0.05)):
        if done():
            return
        await asyncio.sleep(0.05)
    await settle(pilot)
    assert done()


async def test_b_serves_the_league_shows_where_and_b_again_stops_it() -> None:
    data_home().mkdir(parents=True, exist_ok=True)
    with open_league() as league:
        new_night(league, resolve_track("beginner-oval"), name="friday")
    app = create_app(start="league")
    async with app.run_test(size=(80, 24)) as pilot:
        notes = Notifications(app)
        nights = await the_nights_screen(pilot)
        assert isinstance(nights, NightsScreen)
        await pilot.press("b")
        pages = nights.web_pages
        await _until(pilot, lambda: pages.running and "Web pages at" in str(_note(nights).render()))
        address = pages.address
        assert address.startswith("http://127.0.0.1:")
        assert "only this machine can open them" in notes.text("information")
        page = await asyncio.to_thread(_read, address + "night")
        assert "friday" in page
        process = pages.process
        assert process is not None
        await pilot.press("b")
        await _until(pilot, lambda: process.poll() is not None and not pages.running)
        await _until(pilot, lambda: _note(nights).has_class("-hidden"))
        assert "The web pages are stopped." in notes.text("information")
        await pilot.press("b")  # again, and then the app quits with it running
        await _until(pilot, lambda: pages.running)
        process = pages.process
        assert process is not None
    assert process.wait(10) is not None  # stopped with the app


def _note(nights: NightsScreen) -> Static:
    return nights.query_one("#web-note", Static)


def _read(url: str) -> str:
    with urllib.request.urlopen(url, timeout=10) as answer:
        return str(answer.read().decode())


def test_a_server_stopped_while_it_starts_is_never_left_running() -> None:
    # b and then Esc at once: the screen is gone (and its pages stopped) before the
    # server has said where it listens. It must not stay up with nothing to stop it.
    import threading

    from racer_tui.app.web_pages import WebPages

    data_home().mkdir(parents=True, exist_ok=True)
    open_league().close()
    pages = WebPages()
    said: list[str] = []
    starting = threading.Thread(target=lambda: said.append(pages.start(None)))
    starting.start()
    while not pages.starting:
        pass
    pages.stop()  # while it starts
    starting.join(60)
    assert said == [""]  # it came up, was stopped, and says nothing to show
    assert pages.process is None and not pages.running
    assert not any(
        "racer_tui.cli.main serve" in " ".join(child.cmdline())
        for child in psutil.Process().children(recursive=True)
        if child.is_running() and child.status() != psutil.STATUS_ZOMBIE
    )

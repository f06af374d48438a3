"""The web pages in a real browser: headless Chromium (Debian's `chromium` package) loads
each page at a projector's size and a phone's, and what it rendered is read back from
its DOM: hostile names are text, no element came from them, and the live page follows a
heat from the start to the finish as its script fills it in.

Skipped where Chromium is not installed (`apt install chromium`)."""

from __future__ import annotations

import shutil
import struct
import subprocess
import time
from html.parser import HTMLParser
from pathlib import Path

import pytest

from league import nights
from league.live_heat import LiveHeatWriter, LiveLap, live_heat_path
from league.live_match import LiveCar, LiveIncident, LiveMatchWriter, live_match_path
from league.opening import open_league
from tests.racer_tui.web.conftest import IMAGE, LONG, SCRIPT, Served

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="Chromium is not installed here (Debian: apt install chromium)"
)
SIZES = ((1920, 1080), (390, 844))
PAGES = ("/", "/night", "/live", "/overlay")
# Chromium waits this long (ms) after loading before it dumps or shoots: the live page's
# script has run by then.
SETTLE_MS = 1500


def _chromium(url: str, *options: str) -> str:
    assert CHROMIUM is not None
    headless = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    done = subprocess.run(
        [CHROMIUM, *headless, f"--timeout={SETTLE_MS}", *options, url],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


class Rendered(HTMLParser):
    """A dumped DOM: its elements (tag and attributes) and its text."""

    def __init__(self, dom: str) -> None:
        super().__init__()
        self.elements: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []
        self.feed(dom)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.elements.append((tag, dict(attrs)))

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    @property
    def state(self) -> str | None:
        """The heat's state as the live pages' script marked it on the body."""
        return next(attrs for tag, attrs in self.elements if tag == "body").get("data-state")


def _rendered(url: str) -> Rendered:
    return Rendered(_chromium(url, "--dump-dom"))


def _png_size(path: Path) -> tuple[int, int]:
    header = path.read_bytes()[:24]
    assert header[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", header[16:24])
    return width, height


def _writer(served: Served) -> LiveHeatWriter:
    with open_league(served.db) as league:
        [night] = nights.list_nights(league)
    path = live_heat_path(served.db, night.id)
    return LiveHeatWriter(
        path, night_id=night.id, heat_id="H9", heat_number=4, racer=IMAGE, car="reference"
    )


def _publish(writer: LiveHeatWriter, state: str, laps: tuple[LiveLap, ...]) -> None:
    writer.publish(
        state=state,
        time_left=0.0 if state == "over" else 200.0,
        lap=len(laps) + (state != "over"),
        lap_time=0.0,
        best_lap=min((lap.time_seconds for lap in laps), default=None),
        offtracks=0,
        limit=3,
        laps=laps,
        car_at=None if state == "over" else (0.5, 0.5),
    )


def test_every_page_shows_hostile_names_as_text_at_both_sizes(
    served: Served, tmp_path: Path
) -> None:
    _publish(_writer(served), "running", ())
    for path in PAGES:
        page = _rendered(served.url + path)
        # No element came from a name: the only scripts are the page's own.
        assert not [tag for tag, _ in page.elements if tag in ("img", "iframe", "object")]
        scripts = [attrs for tag, attrs in page.elements if tag == "script"]
        assert all(
            attrs.get("src") == "/live.js" or attrs.get("type") == "application/json"
            for attrs in scripts
        ), path
        shown = "".join(page.text)
        assert IMAGE in shown or SCRIPT in shown, path
        for width, height in SIZES:
            shot = tmp_path / f"{path.strip('/') or 'leaderboard'}-{width}x{height}.png"
            _chromium(served.url + path, f"--window-size={width},{height}", f"--screenshot={shot}")
            assert _png_size(shot) == (width, height)


def test_the_live_page_follows_a_heat_from_start_to_finish(served: Served) -> None:
    writer = _writer(served)
    _publish(writer, "ready", ())
    page = _rendered(served.url + "/live")
    assert page.state == "ready"
    shown = "".join(page.text)
    assert IMAGE in shown and "No heat running" not in shown

    laps = (LiveLap(9.7, 0.0, 0, True), LiveLap(12.9, 3.0, 1, True))
    _publish(writer, "running", laps)
    page = _rendered(served.url + "/live")
    assert page.state == "running"
    rows = [attrs for tag, attrs in page.elements if tag == "tr"]
    assert len(rows) == 1 + len(laps)  # the header and a row a lap
    assert "9.700" in "".join(page.text)

    _publish(writer, "over", laps)
    page = _rendered(served.url + "/overlay")
    assert page.state == "over"  # the racer's card shows
    writer.clear()
    page = _rendered(served.url + "/live")
    assert page.state == "none"
    assert "No heat running" in "".join(page.text)


def test_the_live_page_shows_a_bracket_match_car_by_car(served: Served, tmp_path: Path) -> None:
    with open_league(served.db) as league:
        [night] = nights.list_nights(league)
    match = LiveMatchWriter(
        live_match_path(served.db, night.id),
        night_id=night.id,
        match_id="W1-1",
        title="Final",
        lap_count=3,
        racers=[(IMAGE, "reference"), (SCRIPT, "reference")],
    )
    cars = [
        LiveCar("", "", 2, 1, 0.5, "crash", False, (0.5, 0.5), 90.0),
        LiveCar("", "", 1, 2, None, "", False, (1.0, 0.2), 0.0),
    ]
    crash = [LiveIncident(29, "crash", 0, 1)]

    def on_air() -> None:  # written again, as the race view does, so it never goes stale
        match.publish(state="running", clock=30.0, cars=cars, incidents=crash, now=time.time() + 1)

    on_air()
    page = _rendered(served.url + "/live")
    assert page.state == "match"
    assert not [tag for tag, _ in page.elements if tag in ("img", "iframe", "object")]
    items = [attrs for tag, attrs in page.elements if tag == "li"]
    assert len(items) == 2
    shown = "".join(page.text)
    assert f"1 {SCRIPT}  laps 2/3" in shown and f"2 {IMAGE}  laps 1/3  +0.50 s  crash" in shown
    assert f"{IMAGE} ran into {SCRIPT} and is held" in shown
    for width, height in SIZES:
        shot = tmp_path / f"match-{width}x{height}.png"
        on_air()
        _chromium(served.url + "/live", f"--window-size={width},{height}", f"--screenshot={shot}")
        assert _png_size(shot) == (width, height)
    match.clear()


def test_names_no_league_would_take_still_render_as_text(served: Served) -> None:
    # A right-to-left override and 10,000 characters cannot be a racer's name (the league
    # refuses them, here and on every pull), so they are written into the database behind
    # its back: whatever a newer or broken racer-tui might let through stays text.
    import sqlite3

    hostile = "\u202eevil" + "x" * 10_000
    with sqlite3.connect(served.db) as conn:
        conn.execute("UPDATE racers SET display_name = ? WHERE name = ?", (hostile, LONG))
    try:
        page = _rendered(served.url + "/")
        assert hostile in "".join(page.text)
        assert not [tag for tag, _ in page.elements if tag in ("img", "iframe", "object")]
    finally:
        with sqlite3.connect(served.db) as conn:
            conn.execute("UPDATE racers SET display_name = ? WHERE name = ?", (LONG, LONG))

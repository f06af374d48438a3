"""The web server's fixture: `racer-tui serve` started as a host starts it, on loopback,
over a league whose racers' names are hostile, for every test of the module."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from league import nights
from league.opening import open_league
from league.races import record_race
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result

SCRIPT = "<script>alert(1)</script>"
IMAGE = '"><img src=x onerror=alert(1)>'
LONG = "L" * 100  # the longest name a racer can have


def get(url: str) -> tuple[int, dict[str, str], str]:
    """Status, headers and body of a GET, errors included."""
    try:
        with urllib.request.urlopen(url, timeout=10) as answer:
            return answer.status, dict(answer.headers), answer.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, dict(error.headers), error.read().decode()


@dataclass(frozen=True)
class Served:
    url: str
    first_line: str
    db: Path


@contextmanager
def serving(db: Path, home: Path) -> Iterator[Served]:
    """`racer-tui serve --port 0` over `db`, with `home` as its data folder, until the end
    of the block; then SIGTERM (as the app stops its own server), which must stop it."""
    env = {**os.environ, "RACER_TUI_HOME": str(home), "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "racer_tui.cli.main", "serve", "--db", str(db), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert process.stdout is not None
        first = process.stdout.readline()
        found = re.search(r"http://127\.0\.0\.1:\d+/", first)
        assert found, f"no address in {first!r}"
        yield Served(found.group(0).rstrip("/"), first, db)
    finally:
        # Not Ctrl+C (SIGINT): a test run started in the background ignores it, and so do
        # its children. The server ends its requests, then the signal ends it: no traceback.
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == -signal.SIGTERM
        assert process.stderr is not None and "Traceback" not in process.stderr.read()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    """One league for the module: a night whose three racers' names are hostile."""
    home = tmp_path_factory.mktemp("serve-home")
    db = home / "league.db"
    with open_league(db) as league:
        night = nights.new_night(league, resolve_track(TRACK), name=f"Friday {SCRIPT}")
        for racer, times in ((SCRIPT, [10.0, 10.4]), (IMAGE, [10.2, 9.9]), (LONG, [11.0])):
            result = race_result(racer, times, model=f"car of {racer[:20]}")
            record_race(league, result, night.id)
        league.conn.commit()
    with serving(db, home) as server:
        yield server

"""`racer-tui serve` as a host starts it: a real server on loopback, asked over HTTP. The
pages and their JSON show the league as the command line does, names that came from
other machines stay text, and nothing a visitor sends can change the league."""

from __future__ import annotations

import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from league import nights
from league.opening import open_league
from league.races import record_race
from racer_tui.web.server import CONTENT_SECURITY_POLICY, read_only_league
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result

SCRIPT = "<script>alert(1)</script>"
IMAGE = '"><img src=x onerror=alert(1)>'
LONG = "L" * 100  # the longest name a racer can have


@dataclass(frozen=True)
class Served:
    url: str
    first_line: str
    db: Path


def _get(url: str) -> tuple[int, dict[str, str], str]:
    try:
        with urllib.request.urlopen(url, timeout=10) as answer:
            return answer.status, dict(answer.headers), answer.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, dict(error.headers), error.read().decode()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    home = tmp_path_factory.mktemp("serve-home")
    db = home / "league.db"
    with open_league(db) as league:
        night = nights.new_night(league, resolve_track(TRACK), name=f"Friday {SCRIPT}")
        for racer, times in ((SCRIPT, [10.0, 10.4]), (IMAGE, [10.2, 9.9]), (LONG, [11.0])):
            result = race_result(racer, times, model=f"car of {racer[:20]}")
            record_race(league, result, night.id)
        league.conn.commit()
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
        process.send_signal(signal.SIGINT)
        # Ctrl+C stops it as it stops any command: exit status 130, no traceback.
        assert process.wait(timeout=10) == 130
        assert process.stderr is not None and "Traceback" not in process.stderr.read()


def test_it_says_where_it_listens_and_who_can_open_it(served: Served) -> None:
    assert "read-only" in served.first_line
    assert "only this machine can open it" in served.first_line


def test_the_leaderboard_ranks_as_the_command_line_and_keeps_names_text(served: Served) -> None:
    status, headers, page = _get(served.url + "/")
    assert status == 200
    assert headers["content-security-policy"] == CONTENT_SECURITY_POLICY
    assert "<script>" not in page and "<img" not in page
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "&#34;&gt;&lt;img src=x onerror=alert(1)&gt;" in page
    assert LONG in page
    status, _, text = _get(served.url + "/api/leaderboard")
    [board] = json.loads(text)["boards"]
    # Best lap first: the image racer's 9.9 s, then the script racer's 10.0 s.
    assert [(row["rank"], row["racer"]) for row in board["rows"]] == [
        (1, IMAGE),
        (2, SCRIPT),
        (3, LONG),
    ]
    assert board["track"] == TRACK
    status, _, text = _get(served.url + "/api/leaderboard?by=total")
    assert status == 200 and json.loads(text)["ranking"] == "total_time"


def test_the_night_shows_its_standings(served: Served) -> None:
    status, _, page = _get(served.url + "/night")
    assert status == 200
    assert "Friday &lt;script&gt;" in page and "Standings so far" in page
    _, _, text = _get(served.url + "/api/night")
    night = json.loads(text)
    assert [s["racer"] for s in night["standings"]] == [IMAGE, SCRIPT, LONG]
    assert [s["points"] for s in night["standings"]][:2] == [25, 18]


def test_a_bad_question_gets_a_sentence_and_nothing_can_be_sent(served: Served) -> None:
    status, _, text = _get(served.url + "/api/leaderboard?by=fastest")
    assert status == 400
    assert json.loads(text) == {"error": "by must be one of best, average, total, not 'fastest'."}
    status, _, page = _get(served.url + "/night?id=no-such-night")
    assert status == 404 and "there is no league night" in page
    request = urllib.request.Request(served.url + "/", data=b"x=1", method="POST")
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(request, timeout=10)
    assert refused.value.code == 405
    assert refused.value.headers["content-security-policy"] == CONTENT_SECURITY_POLICY


def test_the_league_is_opened_so_that_nothing_can_write(tmp_path: Path) -> None:
    db = tmp_path / "league.db"
    open_league(db).close()
    with read_only_league(db) as league, pytest.raises(sqlite3.Error):
        league.conn.execute("INSERT INTO racers (name) VALUES ('x')")


def test_a_port_in_use_is_one_sentence(served: Served, tmp_path: Path) -> None:
    port = served.url.rsplit(":", 1)[1]
    command = ["serve", "--db", str(served.db), "--port", port]
    finished = subprocess.run(
        [sys.executable, "-m", "racer_tui.cli.main", *command],
        check=False,
        capture_output=True,
        text=True,
        env={**os.environ, "RACER_TUI_HOME": str(tmp_path)},
        timeout=60,
    )
    assert finished.returncode == 2
    assert finished.stderr.startswith(f"racer-tui: cannot listen on 127.0.0.1 port {port}")
    assert "Traceback" not in finished.stderr

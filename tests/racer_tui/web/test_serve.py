"""`racer-tui serve` as a host starts it: a real server on loopback, asked over HTTP. The
pages and their JSON show the league as the command line does, names that came from
other machines stay text, and nothing a visitor sends can change the league."""

from __future__ import annotations

import json
import os
import re
import sqlite3
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from league import nights
from league.live_heat import LiveHeatWriter, LiveLap, live_heat_path
from league.live_match import LiveCar, LiveIncident, LiveMatchWriter, live_match_path
from league.opening import open_league
from league.seasons import new_season
from racer_tui.web.server import CONTENT_SECURITY_POLICY, read_only_league
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK
from tests.racer_tui.web.conftest import IMAGE, LONG, SCRIPT, Served, get, serving


def test_it_says_where_it_listens_and_who_can_open_it(served: Served) -> None:
    assert "read-only" in served.first_line
    assert "only this machine can open it" in served.first_line


def test_the_leaderboard_ranks_as_the_command_line_and_keeps_names_text(served: Served) -> None:
    status, headers, page = get(served.url + "/")
    assert status == 200
    assert headers["content-security-policy"] == CONTENT_SECURITY_POLICY
    assert "<script>" not in page and "<img" not in page
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "&#34;&gt;&lt;img src=x onerror=alert(1)&gt;" in page
    assert LONG in page
    status, _, text = get(served.url + "/api/leaderboard")
    [board] = json.loads(text)["boards"]
    # Best lap first: the image racer's 9.9 s, then the script racer's 10.0 s.
    assert [(row["rank"], row["racer"]) for row in board["rows"]] == [
        (1, IMAGE),
        (2, SCRIPT),
        (3, LONG),
    ]
    assert board["track"] == TRACK
    status, _, text = get(served.url + "/api/leaderboard?by=total")
    assert status == 200 and json.loads(text)["ranking"] == "total_time"


def test_the_night_shows_its_standings(served: Served) -> None:
    status, _, page = get(served.url + "/night")
    assert status == 200
    assert "Friday &lt;script&gt;" in page and "Standings so far" in page
    _, _, text = get(served.url + "/api/night")
    night = json.loads(text)
    assert [s["racer"] for s in night["standings"]] == [IMAGE, SCRIPT, LONG]
    assert [s["points"] for s in night["standings"]][:2] == [25, 18]


def test_a_bad_question_gets_a_sentence_and_nothing_can_be_sent(served: Served) -> None:
    status, _, text = get(served.url + "/api/leaderboard?by=fastest")
    assert status == 400
    assert json.loads(text) == {"error": "by must be one of best, average, total, not 'fastest'."}
    status, _, page = get(served.url + "/night?id=no-such-night")
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


def _night_writer(served: Served) -> LiveHeatWriter:
    with open_league(served.db) as league:
        [night] = nights.list_nights(league)
    return LiveHeatWriter(
        live_heat_path(served.db, night.id),
        night_id=night.id,
        heat_id="H4",
        heat_number=4,
        racer=IMAGE,
        car="reference",
    )


def _publish(writer: LiveHeatWriter, laps: tuple[LiveLap, ...]) -> None:
    assert writer.publish(
        state="running",
        time_left=180.0,
        lap=len(laps) + 1,
        lap_time=2.0,
        best_lap=min((lap.time_seconds for lap in laps), default=None),
        offtracks=1,
        limit=3,
        laps=laps,
        car_at=(0.5, 0.5),
    )


def test_the_live_heat_is_served_and_pushed_as_it_changes(served: Served) -> None:
    writer = _night_writer(served)
    _publish(writer, (LiveLap(9.5, 0.0, 0, True),))
    status, _, text = get(served.url + "/api/live")
    live = json.loads(text)
    assert status == 200 and live["heat"]["racer"] == IMAGE
    assert live["heat"]["laps"] == [
        {"time_seconds": 9.5, "penalty_seconds": 0.0, "offtracks": 0, "counts": True}
    ]
    # The night's leader is the image racer's 9.9 s best lap: this heat is 0.4 s ahead.
    assert live["leader"] == {"racer": IMAGE, "score": 9.9}
    assert live["gap_to_leader"] == -0.4
    assert live["heat"]["car_on_map"] is not None  # the night's track is drawn here
    with urllib.request.urlopen(served.url + "/api/live/stream", timeout=10) as stream:
        assert stream.headers["content-type"].startswith("text/event-stream")
        first = json.loads(stream.readline().decode().removeprefix("data: "))
        assert first["heat"]["lap"] == 2
        _publish(writer, (LiveLap(9.5, 0.0, 0, True), LiveLap(9.2, 0.0, 0, True)))
        lap = 2
        while lap == 2:  # the stream's next events, until the new lap's arrives
            line = stream.readline().decode()
            if line.startswith("data: "):
                lap = json.loads(line.removeprefix("data: "))["heat"]["lap"]
        assert lap == 3
    writer.clear()
    assert json.loads(get(served.url + "/api/live")[2])["heat"] is None


def test_a_bracket_match_racing_now_is_served_with_its_cars_on_the_map(served: Served) -> None:
    with open_league(served.db) as league:
        [night] = nights.list_nights(league)
    writer = LiveMatchWriter(
        live_match_path(served.db, night.id),
        night_id=night.id,
        match_id="W1-1",
        title="Final",
        lap_count=3,
        racers=[(IMAGE, "reference"), ("bob", "rival.racer-bundle")],
    )
    cars = [
        LiveCar("", "", 2, 1, 0.5, "crash", False, (0.5, 0.5), 90.0),
        LiveCar("", "", 1, 2, None, "", False, (1.0, 0.2), 0.0),
    ]
    assert writer.publish(
        state="running", clock=30.0, cars=cars, incidents=[LiveIncident(29.0, "crash", 0, 1)]
    )
    live = json.loads(get(served.url + "/api/live")[2])
    match = live["match"]
    assert (match["title"], match["match_id"], match["state"]) == ("Final", "W1-1", "running")
    assert [car["racer"] for car in match["cars"]] == [IMAGE, "bob"]  # grid order
    assert [car["place"] for car in match["cars"]] == [2, 1]
    assert all(car["on_map"] is not None for car in match["cars"])  # drawn on the track
    assert match["incidents"] == [{"clock": 29.0, "kind": "crash", "car": 0, "other": 1}]
    page = get(served.url + "/live")[2]
    assert 'id="match-cars"' in page and 'id="match-car-1"' in page
    # The names reach the page only as data, escaped, for the script to set as text.
    assert "<img" not in page.split('id="live-now"')[0].split("<main")[-1]
    writer.clear()
    assert json.loads(get(served.url + "/api/live")[2])["match"] is None


@pytest.mark.parametrize(
    ("path", "part"), [("/live", '<svg class="map"'), ("/overlay", "lower-third")]
)
def test_the_live_pages_run_only_their_own_script(served: Served, path: str, part: str) -> None:
    _publish(_night_writer(served), ())
    status, headers, page = get(served.url + path)
    assert status == 200 and part in page
    scripts = re.findall(r"<script[^>]*>", page)
    assert scripts == [
        '<script src="/live.js" defer>',
        '<script id="live-now" type="application/json">',
    ]
    # Names inside the page's data are escaped for the markup they sit in.
    assert "\\u003cimg src=x onerror=alert(1)\\u003e" in page and "<img" not in page
    status, headers, script = get(served.url + "/live.js")
    assert status == 200 and headers["content-type"].startswith("text/javascript")
    assert "innerHTML" not in script  # values are set as text


def test_a_season_s_night_shows_its_running_heat_and_the_season_s_points(
    tmp_path: Path,
) -> None:

    db = tmp_path / "league.db"
    with open_league(db) as league:
        season = new_season(league, "Spring")
        night = nights.new_night(league, resolve_track(TRACK), name="week 1", season=season.id)
        for racer in ("ada", "bob"):
            nights.add_entrant(league, night, racer, "reference")
        _, second = nights.draw_heats(league, night, seed=1)
        league.conn.commit()
    writer = LiveHeatWriter(
        live_heat_path(db, night.id),
        night_id=night.id,
        heat_id=second.id,
        heat_number=second.position,
        racer=second.entrant.display_name,
        car="reference",
    )
    _publish(writer, ())
    with serving(db, tmp_path) as server:
        page = get(f"{server.url}/night?id={night.id}")[2]
        document = json.loads(get(f"{server.url}/api/night?id={night.id}")[2])
    # The heat on track is marked, the other waits; the season has no closed night yet.
    assert page.count("running now") == 1 and page.count("waiting") == 1
    assert document["season"] == {
        "id": season.id,
        "name": "Spring",
        "points": list(season.points),
        "nights": 0,
        "standings": [],
    }
    assert "Season Spring: 0 closed nights" in page

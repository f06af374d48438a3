"""The heat running now, as its screen writes it for the night's projector: what is
written, how often, and what a reader refuses (stale, foreign or damaged files)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from league.live_heat import (
    HEARTBEAT_SECONDS,
    MAX_BYTES,
    STALE_SECONDS,
    LiveHeatWriter,
    live_heat_path,
    read_live_heat,
)

NIGHT = "01NIGHT"


def writer(tmp_path: Path) -> LiveHeatWriter:
    path = live_heat_path(tmp_path / "league.db", NIGHT)
    return LiveHeatWriter(
        path, night_id=NIGHT, heat_id="H1", heat_number=2, racer="[b]Ada", car="c"
    )


def publish(live: LiveHeatWriter, now: float, *, lap: int = 1, state: str = "running") -> bool:
    return live.publish(
        state=state,
        time_left=200.0,
        lap=lap,
        lap_time=3.5,
        best_lap=None,
        offtracks=1,
        limit=3,
        now=now,
    )


def test_a_heat_is_written_beside_the_league_and_read_back(tmp_path: Path) -> None:
    live = writer(tmp_path)
    assert live.path == tmp_path / "live-heats" / f"{NIGHT}.json"
    assert publish(live, 100.0)
    heat = read_live_heat(live.path, NIGHT, now=101.0)
    assert heat is not None
    assert (heat.heat_number, heat.racer, heat.lap, heat.offtracks, heat.limit) == (
        2,
        "[b]Ada",
        1,
        1,
        3,
    )
    assert read_live_heat(live.path, "ANOTHER", now=101.0) is None  # another night's heat
    live.clear()
    assert not live.path.exists() and read_live_heat(live.path, NIGHT, now=101.0) is None


def test_changes_are_written_at_once_and_a_standing_heat_beats_like_a_heart(
    tmp_path: Path,
) -> None:
    live = writer(tmp_path)
    assert publish(live, 100.0)
    assert not publish(live, 100.1)  # nothing changed, heartbeat not due
    assert publish(live, 100.2, lap=2)  # a new lap: at once
    assert publish(live, 100.3, lap=2, state="paused")  # paused: at once
    assert not publish(live, 100.4, lap=2, state="paused")
    assert publish(live, 100.3 + HEARTBEAT_SECONDS, lap=2, state="paused")
    assert live.writes == 4


def test_a_writer_that_stopped_is_a_heat_no_longer_running(tmp_path: Path) -> None:
    live = writer(tmp_path)
    publish(live, 100.0)
    assert read_live_heat(live.path, NIGHT, now=100.0 + STALE_SECONDS) is not None
    assert read_live_heat(live.path, NIGHT, now=100.1 + STALE_SECONDS) is None  # killed
    assert read_live_heat(live.path, NIGHT, now=100.0 - STALE_SECONDS - 1) is None


@pytest.mark.parametrize(
    "damage",
    [
        lambda data: "not json {",
        lambda data: json.dumps([data]),
        lambda data: json.dumps({**data, "state": "flying"}),
        lambda data: json.dumps({**data, "lap": -1}),
        lambda data: json.dumps({**data, "lap": True}),
        lambda data: json.dumps({**data, "time_left": "soon"}),
        lambda data: json.dumps({**data, "best_lap": float("nan")}),
        lambda data: json.dumps({**data, "racer": "x" * 1000}),
        lambda data: json.dumps({key: v for key, v in data.items() if key != "car"}),
        lambda data: json.dumps({**data, "pad": "x" * MAX_BYTES}),
        lambda data: json.dumps({**data, "time_left": 10**400}),  # past a float
        lambda data: "[" * 3000,  # nested past the parser's recursion limit
        lambda data: json.dumps({**data, "racer": "Ada\x1b[2J"}),  # a terminal escape
    ],
)
def test_a_damaged_file_is_no_heat_at_all(tmp_path: Path, damage: object) -> None:
    live = writer(tmp_path)
    publish(live, 100.0)
    data = json.loads(live.path.read_text())
    live.path.write_text(damage(data))  # type: ignore[operator]
    assert read_live_heat(live.path, NIGHT, now=100.5) is None


def test_a_write_that_fails_never_stops_the_heat(tmp_path: Path) -> None:
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the folder would go")
    live = LiveHeatWriter(
        live_heat_path(blocked / "league.db", NIGHT),
        night_id=NIGHT,
        heat_id="H1",
        heat_number=1,
        racer="Ada",
        car="c",
    )
    assert not publish(live, 100.0)
    live.clear()  # nothing to remove, and no error either


def test_the_laps_and_the_car_s_place_are_written_and_a_moving_car_often(tmp_path: Path) -> None:
    from league.live_heat import MOVING_SECONDS, LiveLap

    live = writer(tmp_path)
    laps = (LiveLap(12.5, 0.0, 0, True), LiveLap(16.0, 3.0, 1, True))

    def place(now: float, x: float) -> bool:
        return live.publish(
            state="running",
            time_left=200.0,
            lap=3,
            lap_time=1.0,
            best_lap=12.5,
            offtracks=0,
            limit=3,
            laps=laps,
            car_at=(x, -2.0),
            now=now,
        )

    assert place(100.0, 1.0)
    assert not place(100.0 + MOVING_SECONDS / 2, 1.5)  # moved, but not yet due
    assert place(100.0 + MOVING_SECONDS * 1.01, 2.0)  # moved and due: well before a heartbeat
    heat = read_live_heat(live.path, NIGHT, now=100.5)
    assert heat is not None and (heat.laps, heat.car_at) == (laps, (2.0, -2.0))
    # A file of an earlier writer (no laps, no place) still reads; a damaged lap does not.
    data = json.loads(live.path.read_text())
    del data["laps"], data["car_at"]
    live.path.write_text(json.dumps(data))
    earlier = read_live_heat(live.path, NIGHT, now=100.5)
    assert earlier is not None and (earlier.laps, earlier.car_at) == ((), None)
    for damage in (
        [{"time_seconds": -1, "penalty_seconds": 0, "offtracks": 0, "counts": True}],
        [{"time_seconds": 1}],
        "laps",
    ):
        live.path.write_text(json.dumps({**data, "laps": damage}))
        assert read_live_heat(live.path, NIGHT, now=100.5) is None
    live.path.write_text(json.dumps({**data, "car_at": [1e300, 0]}))
    assert read_live_heat(live.path, NIGHT, now=100.5) is None

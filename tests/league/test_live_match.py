"""The bracket match racing now, as the venue's projector reads it (league.live_match):
written as it changes and as its cars move, stale when its writer stops, and anything
else in the file is no match running."""

from __future__ import annotations

import json
from pathlib import Path

from league.live_heat import HEARTBEAT_SECONDS, MOVING_SECONDS, STALE_SECONDS
from league.live_match import LiveCar, LiveMatchWriter, live_match_path, read_live_match

NOW = 1000.0


def writer(tmp_path: Path) -> LiveMatchWriter:
    return LiveMatchWriter(
        live_match_path(tmp_path / "league.db", "n1"),
        night_id="n1",
        match_id="W1-1",
        title="Final",
        lap_count=3,
        racers=[("ana", "fast-v2"), ("bob", "rival.racer-bundle")],
    )


def cars(*, bob_ahead: bool = False, at: float = 1.0) -> list[LiveCar]:
    ana = LiveCar("", "", 2 if bob_ahead else 1, 1, 0.4 if bob_ahead else None, "", False, (at, 0))
    bob = LiveCar("", "", 1 if bob_ahead else 2, 1, None if bob_ahead else 0.4, "crash", False)
    return [ana, bob]


def test_a_match_reads_back_as_it_was_written(tmp_path: Path) -> None:
    live = writer(tmp_path)
    assert live.publish(state="running", clock=12.5, cars=cars(), now=NOW)
    match = read_live_match(live.path, "n1", NOW + 1)
    assert match is not None
    said = (match.title, match.match_id, match.state, match.clock)
    assert said == ("Final", "W1-1", "running", 12.5)
    # The names are the writer's, whatever the caller's cars say.
    assert [(c.racer, c.car, c.place, c.held_for) for c in match.running_order()] == [
        ("ana", "fast-v2", 1, ""),
        ("bob", "rival.racer-bundle", 2, "crash"),
    ]
    assert read_live_match(live.path, "another night", NOW + 1) is None
    assert read_live_match(live.path, "n1", NOW + STALE_SECONDS + 1) is None  # writer gone
    live.clear()
    assert not live.path.exists()


def test_it_writes_when_the_order_changes_and_as_the_cars_move(tmp_path: Path) -> None:
    live = writer(tmp_path)
    assert live.publish(state="running", clock=1.0, cars=cars(), now=NOW)
    assert not live.publish(state="running", clock=1.01, cars=cars(), now=NOW + 0.01)
    # An overtake is written at once; a car moving, every MOVING_SECONDS.
    assert live.publish(state="running", clock=1.02, cars=cars(bob_ahead=True), now=NOW + 0.02)
    moved = cars(bob_ahead=True, at=2.0)
    assert not live.publish(state="running", clock=1.03, cars=moved, now=NOW + 0.03)
    assert live.publish(state="running", clock=1.2, cars=moved, now=NOW + 0.02 + MOVING_SECONDS)
    assert live.publish(
        state="running", clock=2.0, cars=moved, now=NOW + 0.02 + MOVING_SECONDS + HEARTBEAT_SECONDS
    )  # the heartbeat, though nothing changed
    assert live.publish(state="over", clock=2.1, cars=moved, now=NOW + 3)


def test_anything_else_in_the_file_is_no_match_running(tmp_path: Path) -> None:
    live = writer(tmp_path)
    live.publish(state="running", clock=1.0, cars=cars(), now=NOW)
    good = json.loads(live.path.read_text())
    spoiled = [
        {**good, "title": "\x1b[2J"},  # an escape sequence for the venue's screen
        {**good, "state": "exploded"},
        {**good, "cars": good["cars"][:1]},  # a match has two cars or more
        {**good, "cars": [{**good["cars"][0], "place": -1}, good["cars"][1]]},
        {**good, "cars": [{**good["cars"][0], "at": [1e308, 0]}, good["cars"][1]]},
        {**good, "clock": float("nan")},
        [good],
    ]
    for data in spoiled:
        live.path.write_text(json.dumps(data))
        assert read_live_match(live.path, "n1", NOW + 1) is None, data
    live.path.write_text("{" * 100_000)
    assert read_live_match(live.path, "n1", NOW + 1) is None

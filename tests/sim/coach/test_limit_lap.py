"""The limit lap: speed profiles under the car's limits, the racing line inside the borders,
the simulator driving it, and the cache."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import Point

import sim.coach.limit_lap as limit_module
from sim.coach.limit_lap import limit_lap
from sim.coach.limits import car_limits
from sim.coach.racing_line import fit_of, road_frame, tightest_turn
from sim.coach.speed_profile import flying_profile, standing_profile
from sim.coach.tracking import drive_line
from sim.deepracer.action_space import Action, ActionSpace
from sim.physics.car import DEEPRACER_CAR
from sim.physics.reference_driver import reference_lap
from sim.tracks.catalog import resolve_track

LIMITS = car_limits()


def naive_profile(corner: np.ndarray, steps: np.ndarray, start: float | None) -> np.ndarray:
    """The forward and backward passes written as plain loops, round the loop enough
    times to settle (or once from `start` m/s, with the next lap after it)."""
    n = len(corner)
    laps = 2 if start is not None else 3
    caps = np.tile(corner**2, laps)
    if start is not None:
        caps[0] = start**2
    gaps = np.tile(steps, laps)[:-1]
    u = caps.copy()
    for i in range(1, len(u)):
        u[i] = min(u[i], u[i - 1] + 2 * LIMITS.acceleration * gaps[i - 1])
    for i in range(len(u) - 2, -1, -1):
        u[i] = min(u[i], u[i + 1] + 2 * LIMITS.braking * gaps[i])
    keep = slice(0, n + 1) if start is not None else slice(n, 2 * n + 1)
    return np.sqrt(u[keep])


def test_the_speed_passes_match_plain_loops() -> None:
    rng = np.random.default_rng(4)
    corner = rng.uniform(0.8, 4.0, 300)
    steps = rng.uniform(0.02, 0.08, 300)
    flying = flying_profile(corner, steps, LIMITS)
    np.testing.assert_allclose(flying.speeds, naive_profile(corner, steps, None), rtol=1e-9)
    standing = standing_profile(corner, steps, LIMITS)
    np.testing.assert_allclose(standing.speeds, naive_profile(corner, steps, 0.0), rtol=1e-9)
    assert standing.speeds[0] == 0.0 and standing.lap_seconds > flying.lap_seconds
    # A flying lap is a loop: it crosses the line at the speed it started with.
    assert flying.speeds[0] == pytest.approx(flying.speeds[-1])


def test_corner_speeds_respect_grip_steering_and_the_action_space() -> None:
    bends = np.array([0.0, 0.5, 1.0, 2.0, 3.0])
    speeds = LIMITS.corner_speed(bends)
    assert speeds[0] == pytest.approx(DEEPRACER_CAR.max_speed * DEEPRACER_CAR.speed_gain)
    assert np.all(speeds[1:] ** 2 * bends[1:] <= DEEPRACER_CAR.grip + 1e-9)  # the tyres hold
    assert speeds[-1] == pytest.approx(LIMITS.crawl)  # tighter than the car can turn
    # A discrete space drives only its own speeds, each with the steering it pairs with.
    space = ActionSpace(
        "discrete", (Action(0.0, 3.0), Action(15.0, 3.0), Action(30.0, 1.0), Action(-30.0, 1.0))
    )
    within = car_limits(DEEPRACER_CAR, space).corner_speed(bends)
    gain = DEEPRACER_CAR.speed_gain
    assert set(np.round(within / gain, 6)) <= {1.0, 3.0}
    assert within[0] == pytest.approx(3.0 * gain) and within[3] == pytest.approx(1.0 * gain)


@pytest.mark.parametrize("name", ["hairpin-circuit", "reinvent_base"])
def test_the_limit_lap_keeps_the_car_on_the_road_and_beats_the_reference(name: str) -> None:
    track = resolve_track(name)
    lap = limit_lap(track)
    half = DEEPRACER_CAR.width / 2.0
    road = track.road
    assert all(road.contains(Point(x, y).buffer(half * 0.99)) for x, y in lap.points[::5])
    assert np.max(np.abs(lap.curvature)) <= tightest_turn(LIMITS) + 1e-9  # drivable
    # Faster than driving the centre line flat out, and than the reference driver.
    frame = road_frame(track)
    centre = fit_of(frame, np.zeros(len(frame.base)), LIMITS)
    assert lap.flying_seconds < centre.profile.lap_seconds
    assert lap.standing_seconds < reference_lap(track).lap_time
    assert lap.flying_seconds < lap.standing_seconds < lap.flying_seconds + 0.5


@pytest.mark.parametrize("name", ["hairpin-circuit", "beginner-oval"])
def test_the_simulator_drives_the_limit_lap_within_three_percent(name: str) -> None:
    track = resolve_track(name)
    lap = limit_lap(track)
    driven = drive_line(track, lap.points, lap.speeds, lap.curvature)
    assert driven.completed, driven.status
    assert abs(driven.flying / lap.flying_seconds - 1.0) <= 0.03
    assert abs(driven.standing / lap.standing_seconds - 1.0) <= 0.05
    assert driven.off_line < 0.10  # it follows the line, not a shortcut of its own


def test_an_action_space_with_slower_speeds_costs_time() -> None:
    track = resolve_track("hairpin-circuit")
    slow = ActionSpace("continuous", steering_range=(-30.0, 30.0), speed_range=(0.5, 2.0))
    assert limit_lap(track, space=slow).flying_seconds > limit_lap(track).flying_seconds + 1.0


def test_limit_laps_are_cached_in_memory_and_on_disk(monkeypatch: pytest.MonkeyPatch) -> None:
    track = resolve_track("hairpin-circuit")
    limit_module._computed.clear()  # another test's, in this process: this home has no file
    first = limit_lap(track)
    assert limit_lap(track) is first
    limit_module._computed.clear()

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("computed again")

    monkeypatch.setattr(limit_module, "optimise_line", refuse)
    again = limit_lap(track)  # from the file
    np.testing.assert_array_equal(again.points, first.points)
    assert math.isclose(again.flying_seconds, first.flying_seconds)
    # A damaged file is no limit lap: computed again.
    (cached,) = (limit_module.data_home() / "cache" / "limit-laps").glob("*.npz")
    cached.write_bytes(b"not an npz")
    limit_module._computed.clear()
    monkeypatch.undo()
    assert limit_lap(track).flying_seconds == pytest.approx(first.flying_seconds)


def test_the_benchmark_prints_its_figures(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from benchmarks.sim import limit_lap as bench_limit

    assert bench_limit.main(["hairpin-circuit", "--json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)["tracks"]
    assert row["track"] == "hairpin-circuit" and row["driven_status"] == "Lap complete"
    assert row["flying_s"] < row["standing_s"] < row["reference_s"]
    assert abs(row["driven_gap_percent"]) <= 3.0
    assert "reinvent_base" in bench_limit.default_tracks()

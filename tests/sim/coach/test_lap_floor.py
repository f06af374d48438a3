"""The lap floor: the fastest lap any DeepRacer car could drive on a track under DeepRacer's
rules, below every honest lap and above the issue's forgeries, worked out once per track."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import sim.coach.lap_floor as floor_module
from sim.coach.lap_floor import cut_loop_metres, cutting_reach, lap_floor, widened_frame
from sim.coach.limit_lap import limit_lap
from sim.coach.plausible import (
    PHYSICAL_TOP_SPEED,
    fastest_possible_lap,
    fastest_possible_lap_by_hash,
    first_impossible_lap,
    hull_floor,
    shortest_loop_metres,
)
from sim.coach.racing_line import road_frame
from sim.physics.car import DEEPRACER_CAR, SIMAPP4_CAR
from sim.physics.labels import PHYSICAL
from sim.physics.reference_driver import reference_lap
from sim.tracks.catalog import resolve_track

# README: a trained model's best lap on re:Invent 2018 (racer-tui's car, physics 4).
TRAINED_MODEL_LAP = 5.342


def test_a_car_may_cut_as_far_as_its_farthest_wheel_centre_is_from_its_centre() -> None:
    # One wheel centre on the road keeps the car on track: the centre may be that wheel's
    # distance beyond the border, the corner of the 0.164 m x 0.160 m wheel rectangle.
    assert cutting_reach() == pytest.approx(math.hypot(0.164 / 2, 0.160 / 2))
    assert cutting_reach() == pytest.approx(max(np.hypot(*DEEPRACER_CAR.wheel_offsets.T)))
    track = resolve_track("speedway")
    wide = widened_frame(track, cutting_reach())
    road = road_frame(track, half_width=0.0)  # the road itself, less the coach's margin
    extra = (wide.high - wide.low) - (road.high - road.low) - 2 * 0.02
    # Wider by the reach on both sides, except inside the tightest bends (never narrower).
    assert np.median(extra) == pytest.approx(2 * cutting_reach(), abs=1e-6)
    assert np.all(extra >= -1e-9)


def test_the_floor_on_reinvent_2018_refuses_the_issues_forgeries_and_no_honest_lap() -> None:
    track = resolve_track("reinvent_base")
    floor = fastest_possible_lap(track)
    assert floor == lap_floor(track)
    assert floor > 4.1  # a race signed with 4.100 s laps, and the 3.900 s evaluation
    assert floor > hull_floor(track)  # higher than the old floor (3.755 s)
    # Every honest lap is above it: the coach's flying limit lap for racer-tui's car, a
    # trained model's best, the reference driver, DeepRacer's real evaluations (16 s).
    assert floor < 0.95 * limit_lap(track).flying_seconds
    assert floor < TRAINED_MODEL_LAP
    assert floor < reference_lap(track).lap_time


@pytest.mark.parametrize("name", ["hairpin-circuit", "beginner-oval", "bowtie-chicane", "speedway"])
def test_honest_laps_clear_the_floor_on_tracks_of_every_shape(name: str) -> None:
    track = resolve_track(name)
    floor = fastest_possible_lap(track)
    assert 0.0 < floor < limit_lap(track).flying_seconds
    assert floor < reference_lap(track).lap_time
    # Never under the shortest loop round the infield less the cut, at 4.08 m/s.
    assert floor >= cut_loop_metres(track, cutting_reach()) / 4.08 - 1e-9
    assert cut_loop_metres(track, cutting_reach()) < shortest_loop_metres(track)


def test_the_floor_is_worked_out_once_then_read_from_memory_and_from_disk(
    monkeypatch: pytest.MonkeyPatch, racer_home: Path
) -> None:
    monkeypatch.setattr(floor_module, "_known", {})
    computed: list[str] = []
    real = floor_module.compute_floor

    def counting(track):  # type: ignore[no-untyped-def]
        computed.append(track.name)
        return real(track)

    monkeypatch.setattr(floor_module, "compute_floor", counting)
    track = resolve_track("hairpin-circuit")
    first = lap_floor(track)
    assert lap_floor(track) == first and computed == ["hairpin-circuit"]  # from memory
    (cached,) = (racer_home / "cache" / "lap-floors").glob("*.json")
    assert cached.name.startswith(track.content_hash[:16])
    assert floor_module.floor_key() in cached.name  # a new floor version is not read
    floor_module.forget_floors()
    assert lap_floor(track) == first and computed == ["hairpin-circuit"]  # from disk
    floor_module.forget_floors()
    cached.write_text(json.dumps({"track_hash": track.content_hash, "floor_seconds": -1}))
    assert lap_floor(track) == first and len(computed) == 2  # a damaged cache: again


def test_a_track_the_coach_finds_no_line_for_keeps_the_hull_floor(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(floor_module, "_known", {})
    monkeypatch.setattr(floor_module, "compute_floor", lambda track: None)
    track = resolve_track("beginner-oval")
    assert fastest_possible_lap(track) == pytest.approx(shortest_loop_metres(track) / 4.0)
    floor_module.forget_floors()  # its "no line" was cached: still the hull
    assert fastest_possible_lap(track) == pytest.approx(hull_floor(track))


def test_a_track_this_machine_does_not_have_has_no_floor() -> None:
    assert fastest_possible_lap_by_hash("0" * 64) is None
    assert first_impossible_lap("0" * 64, "racer-tui/4", [(1, 0.5)]) is None


def test_physical_laps_have_a_floor_of_their_own() -> None:
    track = resolve_track("reinvent_base")
    physical = fastest_possible_lap_by_hash(track.content_hash, PHYSICAL)
    assert physical == pytest.approx(shortest_loop_metres(track) / PHYSICAL_TOP_SPEED)
    assert physical is not None and physical < 3.0 < fastest_possible_lap(track)
    too_fast = first_impossible_lap(track.content_hash, PHYSICAL, [(1, 7.8), (2, 2.0)])
    assert too_fast is not None and too_fast.number == 2
    assert too_fast.sentence("reinvent_base") == (
        "lap 2 of 2.000 s is faster than a real car can drive reinvent_base (no lap under "
        f"{physical:.3f} s is possible there: its shortest loop at 6 m/s, a real car's top "
        "speed)"
    )


def test_the_floors_car_is_more_able_than_every_car_racer_tui_simulates() -> None:
    # A car made faster than the floor's would have honest laps refused: bump the floor.
    able = floor_module.floor_limits()
    for car in (DEEPRACER_CAR, SIMAPP4_CAR):
        assert car.grip <= able.grip
        assert car.max_acceleration <= able.acceleration and car.max_braking <= able.braking
        assert car.max_speed * car.speed_gain <= able.top_speed
        assert car.max_steering_deg <= able.levels[-1].steering_deg
        assert car.effective_wheelbase >= able.effective_wheelbase  # turns no tighter

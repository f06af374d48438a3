"""The reference driver: laps every track cleanly, at the grip limit, deterministically."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sim.deepracer.vocabulary import EpisodeStatus
from sim.physics.car import DEEPRACER_CAR, CarSpec
from sim.physics.reference_driver import (
    ReferenceDriver,
    loop_curvature,
    plan_racing_line,
    reference_lap,
    speed_profile,
)
from sim.physics.simulation import TrackSimulation
from sim.tracks.catalog import list_tracks, resolve_track
from sim.tracks.track import load_track

BUILTIN = [info.name for info in list_tracks() if info.builtin]


@pytest.mark.parametrize("name", BUILTIN)
def test_reference_driver_laps_every_builtin_track(name: str) -> None:
    track = resolve_track(name)
    lap = reference_lap(track)
    assert lap.status == "Lap complete"
    average_speed = track.length / lap.lap_time
    assert 1.5 < average_speed < DEEPRACER_CAR.max_speed


@pytest.mark.parametrize(
    "file", ["reinvent_base.npy", "Bowtie_track.npy", "Oval_track.npy", "reInvent2019_wide.npy"]
)
def test_reference_driver_laps_real_deepracer_tracks(deepracer_dir: Path, file: str) -> None:
    lap = reference_lap(load_track(deepracer_dir / "tracks" / file))
    assert lap.completed
    assert 5.0 < lap.lap_time < 12.0


def test_racing_line_stays_inside_the_road_and_cuts_corners() -> None:
    track = resolve_track("hairpin-circuit")
    line = plan_racing_line(track)
    assert track.on_road(line.points).all()
    # Driven at the same grip limit, the racing line is faster than the centre line.
    centre = track.centerline.point_at(np.arange(0.0, track.length, 0.05))
    centre_curvature = loop_curvature(centre, 3)
    centre_speeds = speed_profile(centre, centre_curvature, DEEPRACER_CAR)
    step = np.hypot(*(np.roll(centre, -1, axis=0) - centre).T)
    centre_time = float(np.sum(step / centre_speeds))
    assert line.planned_lap_time() < 0.95 * centre_time


def test_speed_profile_respects_the_grip_limit() -> None:
    line = plan_racing_line(resolve_track("grand-prix"))
    lateral = line.speeds**2 * np.abs(line.curvature)
    assert lateral.max() <= DEEPRACER_CAR.grip
    assert line.speeds.max() == pytest.approx(DEEPRACER_CAR.max_speed)  # long straight: flat out
    assert line.speeds.min() < 2.5  # hairpins: on the brakes


def test_more_grip_means_a_faster_reference_lap() -> None:
    track = resolve_track("hairpin-circuit")
    normal = reference_lap(track)
    grippy = reference_lap(track, CarSpec(grip=10.0))
    assert grippy.lap_time < normal.lap_time


def test_reference_lap_is_deterministic_and_not_quantised_to_steps() -> None:
    track = resolve_track("speedway")
    first, second = reference_lap(track), reference_lap(track)
    assert first.lap_time == second.lap_time
    steps = first.lap_time * 15
    assert not math.isclose(steps, round(steps), abs_tol=1e-6)


def test_driver_controls_many_cars_at_once() -> None:
    track = resolve_track("beginner-oval")
    sim = TrackSimulation(track, 4)
    sim.reset_all()
    driver = ReferenceDriver(track)
    for _ in range(15 * 5):
        sim.apply(*driver.act(sim))
    assert all(status == EpisodeStatus.IN_PROGRESS for status in sim.status)
    assert (sim.progress > 20).all()

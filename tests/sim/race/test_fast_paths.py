"""A race steps one car, so the simulator, the sensors and the reference driver have
single-car paths in plain floats. They must drive exactly like the batched paths that
training uses: same positions, measurements, episode outcomes and observations."""

from __future__ import annotations

import numpy as np
import pytest

from sim.physics.car import Fleet
from sim.physics.reference_driver import ReferenceDriver
from sim.physics.simulation import TrackSimulation
from sim.race.driver import reference_driver
from sim.sensors.batched import Lidar
from sim.sensors.observations import Observer
from sim.tracks.catalog import resolve_track

TRACKS = ["hairpin-circuit", "bowtie-chicane"]


@pytest.mark.parametrize("name", TRACKS)
def test_one_car_steps_like_a_car_in_a_batch(name: str) -> None:
    track = resolve_track(name)
    alone, batch = TrackSimulation(track, 1), TrackSimulation(track, 2)
    alone.reset_car(0, start_s=0.0)
    batch.reset_cars([0, 1], [0.0, 0.0])
    driver = ReferenceDriver(track)
    outcomes = set()
    for step in range(600):
        steering, speed = driver.act(alone)
        if step % 200 > 175:
            steering = np.full_like(steering, 30.0)  # full lock now and then: off-tracks
        alone.apply(steering, speed)
        batch.apply(np.repeat(steering, 2), np.repeat(speed, 2))
        for name_ in ("s", "distance_from_center", "track_width", "travelled"):
            assert getattr(alone, name_)[0] == pytest.approx(getattr(batch, name_)[0], abs=1e-12)
        assert alone.fleet.x[0] == pytest.approx(batch.fleet.x[0], abs=1e-12)
        assert alone.fleet.yaw[0] == pytest.approx(batch.fleet.yaw[0], abs=1e-12)
        assert np.array_equal(alone.wheels_on[0], batch.wheels_on[0])
        assert alone.segment[0] == batch.segment[0]
        assert alone.left_of_center[0] == batch.left_of_center[0]
        assert alone.status[0] == batch.status[0]
        outcomes.add(str(alone.status[0]))
        if alone.done[0]:
            alone.reset_car(0, start_s=0.0)
            batch.reset_cars([0, 1], [0.0, 0.0])
    assert {"Off track", "Lap complete"} <= outcomes


def test_free_fleet_integrates_like_pymunk() -> None:
    free, boxed = Fleet(1), Fleet(1)
    # A box far away makes the fleet step through pymunk; it is never touched.
    boxed.add_box(100.0, 100.0, 0.0, 0.3, 0.3)
    for fleet in (free, boxed):
        fleet.place(0, 1.0, 2.0, 0.3)
    for step in range(60):
        steering, speed = np.array([25.0 if step < 30 else -10.0]), np.array([3.0])
        for fleet in (free, boxed):
            fleet.set_targets(steering, speed)
            fleet.step()
        assert free.x[0] == pytest.approx(boxed.x[0], abs=1e-12)
        assert free.y[0] == pytest.approx(boxed.y[0], abs=1e-12)
        assert free.yaw[0] == pytest.approx(boxed.yaw[0], abs=1e-12)
        assert free.speed[0] == boxed.speed[0]


@pytest.mark.parametrize("sensor", ["vector", "lidar", "sector_lidar", "camera"])
def test_one_car_observations_match_the_batched_ones(sensor: str) -> None:
    track = resolve_track("hairpin-circuit")
    alone, batch = TrackSimulation(track, 1), TrackSimulation(track, 3)
    seen_alone, seen_batch = Observer(alone, (sensor,)), Observer(batch, (sensor,))
    driver = ReferenceDriver(track)
    alone.reset_car(0, start_s=0.0)
    batch.reset_cars([0, 1, 2], [0.0, 0.0, 0.0])
    for step in range(120):
        steering, speed = driver.act(alone)
        alone.apply(steering, speed)
        batch.apply(np.repeat(steering, 3), np.repeat(speed, 3))
        if step % 10 == 0:
            one, many = seen_alone.observe(), seen_batch.observe()
            assert np.allclose(one[0], many[0], atol=1e-6), step


def test_lidar_for_one_car_reads_what_the_batched_scan_reads() -> None:
    track = resolve_track("bowtie-chicane")
    lidar = Lidar(track)
    rng = np.random.default_rng(3)
    # On the road, near the borders, off it, and far outside the track.
    along = track.centerline.point_at(rng.uniform(0.0, track.length, 150))
    near = along + rng.normal(0.0, 0.35, along.shape)
    far = rng.uniform(np.array(track.bounds[:2]) - 3.0, np.array(track.bounds[2:]) + 3.0, (50, 2))
    points = np.vstack([near, far])
    yaw = rng.uniform(-np.pi, np.pi, len(points))
    batched = lidar.scan(points[:, 0], points[:, 1], yaw)
    for i in range(len(points)):
        single = lidar.scan(points[i : i + 1, 0], points[i : i + 1, 1], yaw[i : i + 1])
        assert np.array_equal(single[0], batched[i]), i


def test_the_race_reference_driver_drives_like_the_reference_driver() -> None:
    track = resolve_track("bowtie-chicane")
    sim = TrackSimulation(track, 1)
    sim.reset_car(0, start_s=0.0)
    fast, original = reference_driver(track), ReferenceDriver(track)
    for _ in range(400):
        action = fast.act(sim)
        steering, speed = original.act(sim)
        assert action.steering_deg[0] == pytest.approx(steering[0], abs=1e-9)
        assert action.speed[0] == pytest.approx(speed[0], abs=1e-9)
        assert action.action_index[0] == -1
        sim.apply(action.steering_deg, action.speed)
        assert str(sim.status[0]) in ("In progress", "Lap complete")

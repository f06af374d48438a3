"""Scripted drivers that make race situations happen on cue."""

from __future__ import annotations

import math

import numpy as np

from sim.physics.car import DEEPRACER_CAR
from sim.physics.simulation import TrackSimulation
from sim.race.driver import DriverAction, reference_driver
from sim.tracks.track import Track


class HardLeft:
    """Full lock left at walking pace: off the track within a few seconds, every time."""

    name = "left"
    content_hash = "left"

    def reset(self, sim: TrackSimulation) -> None:
        del sim

    def act(self, sim: TrackSimulation) -> DriverAction:
        return DriverAction(
            steering_deg=np.full(sim.n, 30.0),
            speed=np.full(sim.n, 1.0),
            action_index=np.full(sim.n, -1, dtype=np.int64),
        )


class ScriptedDriver:
    """The reference driver, except that from each driving step in `swerve_at` (counting
    the driver's own calls from 0) it turns hard right at full speed until it has been put
    back on the track (a put-back car stands still: speed exactly 0)."""

    def __init__(self, track: Track, swerve_at: tuple[int, ...] = (), name: str = "scripted"):
        self._base = reference_driver(track)
        self._swerve_at = set(swerve_at)
        self.name = name
        self.content_hash = f"scripted:{track.content_hash}"
        self.calls = 0
        self._swerving = False

    def reset(self, sim: TrackSimulation) -> None:
        self.calls = 0
        self._swerving = False

    def act(self, sim: TrackSimulation) -> DriverAction:
        step = self.calls
        self.calls += 1
        if step in self._swerve_at:
            self._swerving = True
        elif self._swerving and float(sim.fleet.speed[0]) == 0.0:
            self._swerving = False  # put back after the off-track
        if not self._swerving:
            return self._base.act(sim)
        return DriverAction(
            steering_deg=np.array([-30.0]),
            speed=np.array([4.0]),
            action_index=np.array([-1], dtype=np.int64),
        )


class ReversingDriver:
    """Starts the race turned round (facing against the driving direction) on a ring and
    circles backwards until the race turns it round; then drives round the ring forwards."""

    def __init__(self, radius: float = 2.0, speed: float = 1.0) -> None:
        self.name = "reversing"
        self.content_hash = "reversing"
        self._steer = math.degrees(float(DEEPRACER_CAR.steering_for(1.0 / radius, speed)))
        self._speed = speed
        self.turned_round = False

    def reset(self, sim: TrackSimulation) -> None:
        fleet = sim.fleet
        sim.put(0, float(fleet.x[0]), float(fleet.y[0]), float(fleet.yaw[0]) + math.pi)
        self.turned_round = False
        self._started = False

    def act(self, sim: TrackSimulation) -> DriverAction:
        if self._started and float(sim.fleet.speed[0]) == 0.0:
            self.turned_round = True
        self._started = True
        steer = self._steer if self.turned_round else -self._steer
        return DriverAction(
            steering_deg=np.array([steer]),
            speed=np.array([self._speed]),
            action_index=np.array([-1], dtype=np.int64),
        )

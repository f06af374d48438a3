"""N cars on one track, with DeepRacer's geometry measurements and episode rules.

This is the shared core under the gymnasium env, the vectorised training env, the
reference driver and races: it steps the physics, measures where every car is relative
to the track (all at once, in numpy), keeps DeepRacer's episode bookkeeping (progress from
the episode's start, reversed and immobilized counters), and builds the reward `params`.

Measurements follow DeepRacer's simulator (simapp `bundle/markov/agent_ctrl/utils.py`,
`set_reward_and_metrics`): `x`, `y`, `progress`, `distance_from_center`,
`projection_distance` and `closest_waypoints` use the point 0.14 m ahead of the car centre;
`track_width` is measured across the road at the centre-line point nearest to it; off-track
means all four wheel centres are off the road; `all_wheels_on_track` is False as soon as one
is. Progress counts from the episode's start position, which is where the car *centre* was
placed, so it starts at 0.14 m worth of progress (0.79 % on re:Invent 2018, as DeepRacer's own
sim-trace shows) and a lap completes when the look-ahead point reaches the start again.

Directions: `is_reversed` drives the whole track against its row order (DeepRacer's
REVERSE_DIR); with `EpisodeRules.alternate_direction` each car also turns round every other
episode (ALTERNATE_DRIVING_DIRECTION). `s`, `segment` and `foot` stay positions on the
simulated track's own row order; `reverse` says which cars drive against it this episode,
and what a car's reward function sees (progress, waypoints, left of centre) follows the way
it drives.
"""

from __future__ import annotations

import math
import threading
import time
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray

from sim.deepracer.vocabulary import EpisodeStatus, no_objects
from sim.foundation.arrays import FloatArray
from sim.physics.car import DEEPRACER_CAR, STEP_HZ, STEP_SECONDS, CarSpec, Fleet
from sim.physics.objects.settings import RaceSettings
from sim.physics.objects.world import object_field
from sim.tracks.geometry import PointProjector
from sim.tracks.track import Track

#: DeepRacer measures the car at this point ahead of its centre.
LOOK_AHEAD = 0.14
# Kept between a wheel and the road's edge before the polygon test is skipped: far above
# the rounding of two ways of measuring a distance of a few metres (about 1e-15 m).
_CLEARANCE_MARGIN = 1e-6
_ALL_WHEELS_ON = np.ones((1, 4), dtype=bool)
_ALL_WHEELS_ON.flags.writeable = False


# One reversed copy per track: its projectors and lookup grids take a moment to build.
_REVERSED: weakref.WeakKeyDictionary[Track, Track] = weakref.WeakKeyDictionary()


def reversed_track(track: Track) -> Track:
    """`track` driven the other way round (built once per track, then shared)."""
    found = _REVERSED.get(track)
    if found is None:
        found = _REVERSED[track] = track.reversed()
    return found


class Outcome(IntEnum):
    """How a car's episode ended, as `TrackSimulation.terminal` holds it (an integer array,
    so a whole fleet is judged at once); RUNNING while it goes on."""

    RUNNING = 0
    CRASHED = 1
    OFF_TRACK = 2
    LAP_COMPLETE = 3
    REVERSED = 4
    IMMOBILIZED = 5
    TIME_UP = 6


# The episode status DeepRacer writes for each outcome, indexed by the outcome.
_STATUS = (
    EpisodeStatus.IN_PROGRESS,
    EpisodeStatus.CRASHED,
    EpisodeStatus.OFF_TRACK,
    EpisodeStatus.LAP_COMPLETE,
    EpisodeStatus.REVERSED,
    EpisodeStatus.IMMOBILIZED,
    EpisodeStatus.TIME_UP,
)


@dataclass(frozen=True)
class EpisodeRules:
    """DeepRacer training's episode rules."""

    reversed_steps: int = 15  # consecutive steps of falling progress
    immobilized_steps: int = 15  # consecutive steps moving at most `immobile_distance`
    immobile_distance: float = 0.0003
    start_advance: float = 0.05  # round-robin: each episode starts this fraction further on
    max_steps: int = STEP_HZ * 180  # a 3-minute safety net; a lap ends episodes long before
    # training_params.yaml's CHANGE_START_POSITION (simapp's default: True): each episode
    # starts `start_advance` further round; False starts every episode on the start line.
    change_start: bool = True
    # ALTERNATE_DRIVING_DIRECTION (default False): every other episode drives the other way.
    alternate_direction: bool = False


class TrackSimulation:
    """Steps N independent cars on one track and measures them the way DeepRacer does."""

    def __init__(
        self,
        track: Track,
        n_cars: int = 1,
        *,
        car: CarSpec = DEEPRACER_CAR,
        rules: EpisodeRules | None = None,
        cars_collide: bool = False,
        is_reversed: bool = False,
        lookup_grids: bool = True,
        race: RaceSettings | None = None,
        seed: int = 0,
        first_car: int = 0,
        fleet_cars: int | None = None,
    ) -> None:
        """`lookup_grids=False` for a few hundred steps (one reference lap): the track's
        lines answer by exact tree search until building their lookup grids pays off.
        `race`: an object-avoidance race's boxes or a head-to-bot race's bot cars, each car
        its own (placed from `seed`). `first_car` and `fleet_cars`: these cars are
        `first_car`.. of a training fleet of `fleet_cars` split across processes, and start
        where those cars of one whole fleet would (sim.training.shards)."""
        self.track = track
        self.n = n_cars
        self.first_car = first_car
        self.fleet_cars = n_cars if fleet_cars is None else fleet_cars
        self.car = car
        self.rules = rules or EpisodeRules()
        self.fleet = Fleet(n_cars, car, cars_collide=cars_collide)
        # DeepRacer's REVERSE_DIR: the track's rows are driven in reverse order, so the
        # centre line, its waypoints and the start line all run the other way (simapp
        # `bundle/markov/track_geom/track_data.py` swaps in reversed lines).
        self.is_reversed = is_reversed
        if is_reversed:
            track = reversed_track(track)
            self.track = track
        centre = track.centerline
        self._centre = centre
        self._length = centre.total_length
        self._waypoints = track.waypoints
        self._waypoints_back = self._waypoints[::-1]
        self._segments = len(centre.lengths)
        self._track_length = float(self._length)
        #: The centre line for one-point queries (per-step code for one car).
        lazy = not lookup_grids
        self.centre_projector = PointProjector.of(centre, lazy=lazy)
        self._point_projectors = (
            self.centre_projector,
            PointProjector.of(track.inner_border, lazy=lazy),
            PointProjector.of(track.outer_border, lazy=lazy),
        )
        self._wheel_offsets = [(float(f), float(left)) for f, left in car.wheel_offsets]
        # One car's wheels are all on the road when its centre is within this of a centre
        # segment, per segment (squared; `_wheels_clear`): made when first needed.
        self._clear_sq: list[float] | None = None

        n = n_cars
        self.episode = np.zeros(n, dtype=np.int64)  # episodes started by each car
        self.steps = np.zeros(n, dtype=np.int64)
        self.start_s = np.zeros(n)
        self.travelled = np.zeros(n)  # signed arc length covered since the episode started
        self.status = np.full(n, EpisodeStatus.IN_PROGRESS, dtype=object)
        self.terminal = np.zeros(n, dtype=np.int64)  # outcome code, 0 while running
        self.steering_cmd = np.zeros(n)  # commanded action, as DeepRacer's params report it
        self.speed_cmd = np.zeros(n)
        self._falling = np.zeros(n, dtype=np.int64)
        self._still = np.zeros(n, dtype=np.int64)
        # Measurements, refreshed by `_measure`.
        self.ahead = np.zeros((n, 2))
        self.s = np.zeros(n)
        self.segment = np.zeros(n, dtype=np.intp)
        self.foot = np.zeros((n, 2))
        self.distance_from_center = np.zeros(n)
        self.left_of_center = np.zeros(n, dtype=bool)
        self._track_width = np.zeros(n)
        # Where one car's road is to be measured across, until someone asks (`track_width`).
        self._width_due: tuple[float, float] | None = None
        self.wheels_on = np.ones((n, 4), dtype=bool)
        self._t = np.zeros(n)  # fraction along `segment` of the centre-line foot
        # Cars driving against the track's row order this episode (alternate direction).
        self.reverse = np.zeros(n, dtype=bool)
        self._sign = np.ones(n)
        self._any_reverse = False
        self.objects = object_field(track, race, n, seed=seed)
        # A car that ran into one of its objects this step (DeepRacer's crash).
        self.hit_object = np.zeros(n, dtype=bool)

    # --- episodes ------------------------------------------------------------------------
    def start_position(self, car: int, episode: int) -> float:
        """Arc length where `car` starts `episode`, along the way it drives that episode.

        DeepRacer advances the start by `start_advance` of a lap after every training
        episode when CHANGE_START_POSITION is on (simapp `rollout_agent_ctrl.py`,
        `finish_episode`); here the cars are also spread round the track so that the whole
        fleet sees all of it from the first episode. Off, every episode starts on the line.
        """
        if not self.rules.change_start:
            return 0.0
        fraction = episode * self.rules.start_advance + (self.first_car + car) / self.fleet_cars
        return (fraction % 1.0) * self._length

    def drives_reversed(self, car: int, episode: int) -> bool:
        """Whether `car` drives against the track's row order in `episode`.

        With ALTERNATE_DRIVING_DIRECTION DeepRacer turns the track round after every
        training episode (simapp `finish_episode`); odd cars start the other way so that the
        fleet trains both directions evenly from the start.
        """
        return self.rules.alternate_direction and (episode + self.first_car + car) % 2 == 1

    def reset_car(self, car: int, start_s: float | None = None) -> None:
        """Put a car on the centre line, pointing along the track, for a new episode."""
        self.reset_cars([car], None if start_s is None else [start_s])

    def reset_cars(self, cars: Sequence[int], start_s: Sequence[float] | None = None) -> None:
        """Start new episodes for several cars with one measurement pass.

        `start_s` (arc lengths along the track's row order) places the cars forwards; without
        it each car starts where `start_position` and `drives_reversed` say.
        """
        centre_s = np.zeros(len(cars))
        for k, car in enumerate(cars):
            episode = int(self.episode[car])
            backwards = start_s is None and self.drives_reversed(car, episode)
            if start_s is None:
                s = self.start_position(car, episode)
                if backwards:  # the start line and its round robin run the other way too
                    s = -s
            else:
                s = start_s[k]
            s %= self._length
            objects = self.objects
            if objects is not None and (self.episode[car] > 0 or backwards):
                # Shuffled boxes move, bots start again, and either follow the car's way
                # round (objects are placed for the track's way at the start).
                objects.draw(car, backwards)
            self.episode[car] += 1
            self._set_reverse(car, backwards)
            self._place_along(car, s, backwards)
            if objects is not None:
                self._clear_of_objects(car, s)
            centre_s[k] = s
        index = np.asarray(cars, dtype=np.intp)
        self.steps[index] = 0
        self._falling[index] = 0
        self._still[index] = 0
        self.status[index] = EpisodeStatus.IN_PROGRESS
        self.terminal[index] = 0
        self.steering_cmd[index] = 0.0
        self.speed_cmd[index] = 0.0
        self._measure()
        # Progress counts from where the car centre was placed (simapp's `start_ndist`), but
        # is measured at the look-ahead point: an episode starts 0.14 m into its lap.
        self.start_s[index] = centre_s
        half = self._length / 2.0
        ahead = np.mod(self.s[index] - centre_s + half, self._length) - half
        self.travelled[index] = ahead * self._sign[index]

    def _clear_of_objects(self, car: int, s: float) -> None:
        """Start in the other lane than an object right by the start (as DeepRacer does)."""
        assert self.objects is not None
        pose = self.objects.start_pose(car, s)
        if pose is not None:
            self.fleet.place(car, pose.x, pose.y, pose.heading, 0.0)

    def _set_reverse(self, car: int, backwards: bool) -> None:
        self.reverse[car] = backwards
        self._sign[car] = -1.0 if backwards else 1.0
        self._any_reverse = bool(self.reverse.any())

    def _place_along(self, car: int, s: float, backwards: bool) -> None:
        """Start pose at arc length `s`, pointing the way the car drives (towards the next
        waypoint ahead, simapp's forward difference)."""
        if not backwards:
            self.place(car, s)
            return
        point = self._centre.point_at(np.array([s]))[0]
        # The segment that ends at `s` (at a waypoint, the one driven next going backwards).
        seg = int(np.searchsorted(self._centre.cumulative, s, side="left")) - 1
        seg %= self._segments
        vx, vy = self._centre.vectors[seg]
        self.fleet.place(car, float(point[0]), float(point[1]), math.atan2(-vy, -vx), 0.0)

    def place(self, car: int, s: float, offset: float = 0.0, speed: float = 0.0) -> None:
        """Teleport a car to arc length `s` (and `offset` metres left of the centre line)."""
        point = self._centre.point_at(np.array([s]))[0]
        tangent = self._centre.direction_at(np.array([s]))[0]
        normal = np.array([-tangent[1], tangent[0]])
        x, y = point + offset * normal
        self.fleet.place(car, float(x), float(y), math.atan2(tangent[1], tangent[0]), speed)

    def put(self, car: int, x: float, y: float, yaw: float, speed: float = 0.0) -> None:
        """Place a car at an exact pose (radians) and measure it, keeping its episode going."""
        self.fleet.place(car, x, y, yaw, speed)
        self._measure()

    def put_cars(self, cars: Sequence[int], poses: Sequence[tuple[float, float, float]]) -> None:
        """`put` for several cars, standing, measured once: a training's opponents are put
        on a grid, or held, many at a step."""
        for car, (x, y, yaw) in zip(cars, poses, strict=True):
            self.fleet.place(car, x, y, yaw, 0.0)
        self._measure()

    def reset_all(self) -> None:
        self.reset_cars(range(self.n))

    def pose_all(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, speed: float, steering_deg: float
    ) -> None:
        """Stand every car at a pose at once, as if it had driven there from the start line
        at `speed` with that command (the reward map's cars): one measurement pass for the
        whole fleet, and progress and steps consistent with where each car stands."""
        fleet = self.fleet
        fleet.x[:], fleet.y[:], fleet.yaw[:] = x, y, yaw
        fleet.speed[:] = speed
        self.steering_cmd[:] = steering_deg
        self.speed_cmd[:] = speed
        self._measure()
        start = self.start_position(0, 0)
        self.travelled = np.mod(self.s - start, self._length)
        self.steps = 1 + np.round(self.travelled / max(speed, 0.1) * STEP_HZ).astype(np.int64)

    def continue_episode(self, car: int, travelled: float) -> None:
        """Let a car drive on after its episode ended, as races do (past the line, after a reset).

        Clears the outcome and the reversed/immobilized counters; `travelled` re-bases the
        progress bookkeeping (one lap less after a lap, or where the car was put back).
        """
        self.travelled[car] = travelled
        self.terminal[car] = 0
        self.status[car] = EpisodeStatus.IN_PROGRESS
        self._falling[car] = 0
        self._still[car] = 0

    # --- stepping ------------------------------------------------------------------------
    def apply(self, steering_deg: FloatArray, speed: FloatArray) -> None:
        """Drive every car for one 1/15 s step and update measurements and episode status."""
        if self.n == 1:
            self._apply_one(steering_deg, speed)
            return
        self.steering_cmd[:] = steering_deg
        self.speed_cmd[:] = speed
        before_s = self.s.copy()
        before_x, before_y = self.fleet.x.copy(), self.fleet.y.copy()
        self.fleet.set_targets(steering_deg, speed)
        self.fleet.step()
        if self.objects is not None:
            self.objects.advance(STEP_SECONDS)
        self._measure()
        self.steps += 1
        delta = np.mod(self.s - before_s + self._length / 2.0, self._length) - self._length / 2.0
        if self._any_reverse:
            delta *= self._sign
        self.travelled += delta
        self._falling = np.where(delta < 0.0, self._falling + 1, 0)
        moved = np.hypot(self.fleet.x - before_x, self.fleet.y - before_y)
        self._still = np.where(moved <= self.rules.immobile_distance, self._still + 1, 0)
        self._judge()

    def _measure(self) -> None:
        if self.n == 1:
            self._measure_one()
            return
        fleet = self.fleet
        track = self.track
        self.ahead = fleet.points_ahead(LOOK_AHEAD)
        seg, t, foot = self._centre.project(self.ahead)
        self.segment, self.foot, self._t = seg, foot, t
        self.s = self._centre.arc_length(seg, t)
        rel = self.ahead - foot
        self.distance_from_center = np.hypot(rel[:, 0], rel[:, 1])
        vec = self._centre.vectors[seg]
        cross = vec[:, 0] * rel[:, 1] - vec[:, 1] * rel[:, 0]
        # Left of the way the car drives; exactly on the line is not left either way round.
        self.left_of_center = (cross * self._sign if self._any_reverse else cross) > 0.0
        # Across the road at the centre-line point, as simapp's get_nearest_points does.
        _, _, inner_foot = track.inner_border.project(foot)
        _, _, outer_foot = track.outer_border.project(foot)
        self._track_width = np.hypot(*(outer_foot - inner_foot).T)
        wheels = fleet.wheel_positions().reshape(-1, 2)
        self.wheels_on = track.on_road(wheels).reshape(self.n, 4)
        self._measure_objects()

    def _measure_objects(self) -> None:
        if self.objects is not None:
            fleet = self.fleet
            self.hit_object = self.objects.crashed(fleet.x, fleet.y, fleet.yaw, self.s, self.car)

    @property
    def crashed(self) -> NDArray[np.bool_]:
        """Cars that crashed this step: into an object of theirs, or a body pymunk collides."""
        return np.asarray(self.fleet.crashed | self.hit_object)

    def _judge(self) -> None:
        rules = self.rules
        running = self.terminal == 0
        # DeepRacer's precedence when several things happen in one step: a completed lap
        # first ("the agent might crash at the finish line"), then a crash, then the other
        # rules in the order of simapp's EpisodeStatus (`rollout_agent_ctrl.py`,
        # `_check_for_episode_termination`; `metrics/constants.py`).
        outcomes = np.select(
            [
                self.travelled >= self._length,
                self.crashed,
                ~self.wheels_on.any(axis=1),
                self._still >= rules.immobilized_steps,
                self._falling >= rules.reversed_steps,
                self.steps >= rules.max_steps,
            ],
            [
                Outcome.LAP_COMPLETE,
                Outcome.CRASHED,
                Outcome.OFF_TRACK,
                Outcome.IMMOBILIZED,
                Outcome.REVERSED,
                Outcome.TIME_UP,
            ],
            default=Outcome.RUNNING,
        )
        ended = np.flatnonzero(running & (outcomes > 0))
        for car in ended.tolist():
            self.status[car] = _STATUS[outcomes[car]]
        self.terminal[ended] = outcomes[ended]

    # --- one car: the same steps in plain floats ---------------------------------------------
    # A race drives one car, and numpy's per-call overhead on length-1 arrays costs more
    # than the arithmetic. These do exactly what `apply`, `_measure` and `_judge` do for
    # N cars, and leave the same arrays behind.

    def _apply_one(self, steering_deg: FloatArray, speed: FloatArray) -> None:
        fleet = self.fleet
        self.steering_cmd[:] = steering_deg
        self.speed_cmd[:] = speed
        before_s = float(self.s[0])
        before_x, before_y = float(fleet.x[0]), float(fleet.y[0])
        fleet.set_targets(steering_deg, speed)
        fleet.step()
        if self.objects is not None:
            self.objects.advance(STEP_SECONDS)
        self._measure_one()
        self.steps += 1
        length = self._length
        delta = (float(self.s[0]) - before_s + length / 2.0) % length - length / 2.0
        if self._any_reverse:
            delta = -delta
        self.travelled[0] += delta
        self._falling[0] = self._falling[0] + 1 if delta < 0.0 else 0
        moved = math.hypot(float(fleet.x[0]) - before_x, float(fleet.y[0]) - before_y)
        self._still[0] = self._still[0] + 1 if moved <= self.rules.immobile_distance else 0
        if self.terminal[0] == 0:
            self._judge_one()

    def _measure_one(self) -> None:
        fleet = self.fleet
        x, y, yaw = float(fleet.x[0]), float(fleet.y[0]), float(fleet.yaw[0])
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        ax, ay = x + LOOK_AHEAD * cos_yaw, y + LOOK_AHEAD * sin_yaw
        centre = self.centre_projector
        seg, t, fx, fy = centre.project(ax, ay)
        rel_x, rel_y = ax - fx, ay - fy
        vec_x, vec_y = centre.vectors[seg]
        self._width_due = (fx, fy)
        self.ahead = np.array([[ax, ay]])
        self.segment = np.array([seg], dtype=np.intp)
        self._t = np.array([t])
        self.foot = np.array([[fx, fy]])
        self.s = np.array([centre.arc_length(seg, t)])
        self.distance_from_center = np.array([math.hypot(rel_x, rel_y)])
        cross = vec_x * rel_y - vec_y * rel_x
        self.left_of_center = np.array([(-cross if self._any_reverse else cross) > 0.0])
        if self._wheels_clear(x, y, seg):
            self.wheels_on = _ALL_WHEELS_ON
        else:
            wheel_x = [x + fwd * cos_yaw - left * sin_yaw for fwd, left in self._wheel_offsets]
            wheel_y = [y + fwd * sin_yaw + left * cos_yaw for fwd, left in self._wheel_offsets]
            self.wheels_on = np.asarray(
                shapely.contains_xy(self.track.road, wheel_x, wheel_y), dtype=bool
            ).reshape(1, 4)
        self._measure_objects()

    def _wheels_clear(self, x: float, y: float, seg: int) -> bool:
        """True when one car centred at (x, y) certainly has all four wheels on the road,
        as the polygon test would find: its centre is nearer a centre-line segment than
        that segment's clearance (`Track.centre_clearance`) less the wheels' reach. Tries
        the look-ahead point's segment and the two before it, where the car mostly is;
        False sends the wheels to the polygon test, which costs four times as much."""
        clear_sq = self._clear_sq
        if clear_sq is None:
            reach = max(math.hypot(f, left) for f, left in self._wheel_offsets)
            reach += _CLEARANCE_MARGIN
            clear_sq = self._clear_sq = [
                (c - reach) ** 2 if c > reach else -1.0
                for c in self.track.centre_clearance.tolist()
            ]
        centre = self.centre_projector
        for before in (0, 1, 2):
            candidate = seg - before
            if candidate < 0:
                if not centre.closed:
                    break
                candidate += len(clear_sq)
            limit = clear_sq[candidate]
            if limit > 0.0 and centre.distance_sq(candidate, x, y) < limit:
                return True
        return False

    def _judge_one(self) -> None:
        rules = self.rules
        if self.travelled[0] >= self._length:
            outcome = Outcome.LAP_COMPLETE
        elif self.fleet.crashed[0] or self.hit_object[0]:
            outcome = Outcome.CRASHED
        elif self.wheels_on is not _ALL_WHEELS_ON and not self.wheels_on[0].any():
            outcome = Outcome.OFF_TRACK
        elif self._still[0] >= rules.immobilized_steps:
            outcome = Outcome.IMMOBILIZED
        elif self._falling[0] >= rules.reversed_steps:
            outcome = Outcome.REVERSED
        elif self.steps[0] >= rules.max_steps:
            outcome = Outcome.TIME_UP
        else:
            return
        self.status[0] = _STATUS[outcome]
        self.terminal[0] = outcome

    # --- what the reward function and observers see ----------------------------------------
    @property
    def track_width(self) -> FloatArray:
        """(N,) width of the road across the centre-line point nearest each car's
        look-ahead point, as simapp's `get_nearest_points` measures it.

        One car's is measured when first asked for after a step: a race's camera or
        lidar driver never asks, and the two border projections were a tenth of its
        physics. The same numbers either way."""
        if self._width_due is not None:
            fx, fy = self._width_due
            _, inner, outer = self._point_projectors
            _, _, ix, iy = inner.project(fx, fy)
            _, _, ox, oy = outer.project(fx, fy)
            self._track_width = np.array([math.hypot(ox - ix, oy - iy)])
            self._width_due = None
        return self._track_width

    @property
    def progress(self) -> FloatArray:
        """Percent of a lap covered since the episode started, 0..100 (for display)."""
        return np.clip(self.travelled / self._length * 100.0, 0.0, 100.0)

    @property
    def reward_progress(self) -> FloatArray:
        """`progress` as simapp hands it to the reward function: capped at 100, but below 0
        when the car has backed over its start position (`compute_current_prog`)."""
        return np.minimum(self.travelled * (100.0 / self._length), 100.0)

    @property
    def closest_waypoints(self) -> NDArray[np.intp]:
        """(N, 2) [previous, next] waypoint indexes along the way each car drives.

        simapp finds them by bisecting the waypoints' distances along the centre line
        (`track_geom/utils.py`, `find_prev_next`), so a point exactly on waypoint k gets
        [k, k + 1]: a projection that lands on the end of segment k - 1 counts as k.
        """
        previous = self._previous_waypoints()
        return np.stack([previous, previous + 1], axis=1)

    def _previous_waypoints(self) -> NDArray[np.intp]:
        n_seg = self._segments
        seg, t = self.segment, self._t
        if self._any_reverse:
            back = self.reverse
            seg = np.where(back, n_seg - 1 - seg, seg)
            t = np.where(back, 1.0 - t, t)
        previous: NDArray[np.intp] = seg + (t >= 1.0)
        # The closing waypoint is the first one again.
        return np.remainder(previous, n_seg, out=previous)

    @property
    def any_reversed(self) -> bool:
        """Whether some car drives against the track's row order this episode."""
        return self._any_reverse

    @property
    def direction_sign(self) -> FloatArray:
        """+1 per car driving along the track's row order, -1 per car driving against it."""
        return self._sign

    def driving_tangents(self) -> FloatArray:
        """(N, 2) unit tangents of the centre line at `s`, pointing the way each car drives.

        On a waypoint the tangent is the next segment's, as the car will drive it: for a car
        going against the row order, the segment that ends there."""
        centre = self._centre
        tangent = centre.direction_at(self.s)
        if self._any_reverse:
            back = np.flatnonzero(self.reverse)
            ends = np.searchsorted(centre.cumulative, self.s[back], side="left") - 1
            seg = np.remainder(ends, self._segments)
            tangent[back] = -centre.vectors[seg] / centre.lengths[seg][:, None]
        return tangent

    @property
    def heading_deg(self) -> FloatArray:
        yaw = np.degrees(self.fleet.yaw)
        return np.asarray(180.0 - np.mod(180.0 - yaw, 360.0), dtype=np.float64)

    @property
    def offtrack(self) -> NDArray[np.bool_]:
        return np.asarray(~self.wheels_on.any(axis=1))

    @property
    def done(self) -> NDArray[np.bool_]:
        """Cars whose episode has ended, for any reason."""
        return np.asarray(self.terminal != 0)

    @property
    def timed_out(self) -> NDArray[np.bool_]:
        """Cars whose episode was cut by the step limit (truncated, not terminated)."""
        return np.asarray(self.terminal == Outcome.TIME_UP)

    def all_params(self) -> list[dict[str, Any]]:
        """DeepRacer's reward `params` for every car, every key present."""
        x, y = self.ahead[:, 0].tolist(), self.ahead[:, 1].tolist()
        heading = self.heading_deg.tolist()
        dfc = self.distance_from_center.tolist()
        left = self.left_of_center.tolist()
        width = self.track_width.tolist()
        progress = self.reward_progress.tolist()
        steps = self.steps.tolist()
        speed = self.speed_cmd.tolist()
        steer = self.steering_cmd.tolist()
        all_on: list[bool] = np.all(self.wheels_on, axis=1).tolist()
        offtrack = self.offtrack.tolist()
        crashed = self.crashed.tolist()
        waypoints = [self._waypoints] * self.n
        reversed_flags = [self.is_reversed] * self.n
        projection = self.s
        if self._any_reverse:
            for car in np.flatnonzero(self.reverse).tolist():
                waypoints[car] = self._waypoints_back
                reversed_flags[car] = not self.is_reversed
            projection = np.where(self.reverse, np.mod(-projection, self._length), projection)
        proj = projection.tolist()
        previous = self._previous_waypoints().tolist()
        sim_time = (self.steps * STEP_SECONDS).tolist()
        objects = (
            [no_objects() for _ in range(self.n)]
            if self.objects is None
            else self.objects.all_params(self.s.tolist(), x, y, heading)
        )
        return [
            {
                "all_wheels_on_track": all_on[i],
                "x": x[i],
                "y": y[i],
                "heading": heading[i],
                "distance_from_center": dfc[i],
                "is_left_of_center": left[i],
                "track_width": width[i],
                "track_length": self._track_length,
                "waypoints": waypoints[i],
                "closest_waypoints": [previous[i], previous[i] + 1],
                "progress": progress[i],
                "steps": steps[i],
                "speed": speed[i],
                "steering_angle": steer[i],
                "is_reversed": reversed_flags[i],
                "is_offtrack": offtrack[i],
                "is_crashed": crashed[i],
                "projection_distance": proj[i],
                "sim_time": sim_time[i],
                **objects[i],
            }
            for i in range(self.n)
        ]


# Every so many steps a stepping loop lets the other threads of its process run.
YIELD_EVERY_STEPS = 4


def let_other_threads_run(step: int) -> None:
    """Give up the interpreter for a moment every `YIELD_EVERY_STEPS` steps; call it from
    every loop that steps a simulation and may run in a worker thread (a heat behind the
    app's screens, an evaluation).

    A race in a worker thread made the app's own thread wait 20-130 ms for the
    interpreter at times, whatever the switch interval: compiled code inside a step lets
    go of it for a moment and the stepping thread takes it straight back, and a thread
    waiting for it that sees it change hands does not ask for it again, so it can wait
    through many steps. A zero sleep hands it over for real: beside races back to back,
    the longest wait fell from 133 ms to 7 ms, and the timekeeper's keys answered at p95
    36 ms instead of 52 with a sleep every 4 steps rather than 16. A race alone loses no
    time that this machine can measure to them, and only a worker thread takes them: the
    command line's races (the main thread) have no interface to give way to.
    """
    if step % YIELD_EVERY_STEPS == 0 and threading.current_thread() is not _MAIN_THREAD:
        time.sleep(0)


_MAIN_THREAD = threading.main_thread()

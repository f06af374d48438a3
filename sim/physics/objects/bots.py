"""The bot cars of a head-to-bot race, as deepracer-simapp drives them
(`bot_cars_agent_ctrl.py`; docs/deepracer-objects.md).

Each car of a simulation drives its own episode, so each has its own bots. A bot starts
where DeepRacer starts it (evenly spaced from the minimum distance to 1 m before the line,
shuffled between its neighbours when randomised; lanes alternating, or random when
randomised) and drives its lane at a constant speed measured along the centre line: its
place is (start + elapsed x speed) modulo the lap, in its lane beside that point of the
centre line. Its clock is its car's: it runs while the car drives, stops while the car is
held for a penalty after hitting a bot from behind, as simapp's does (it subtracts the
crash penalties), and stops for `penalty_seconds` when a bot runs into its car from behind
(simapp pauses the bots then).

With lane changes, a bot drives U(lower, upper) seconds in its lane, then moves over to the
other one while it covers LANE_CHANGE_DISTANCE, and so on (simapp's schedule). simapp draws
the move as an interpolating spline from lane to lane; here it is a smoothstep between the
two lanes' points over the same stretch, which starts and ends parallel to the lanes as
the spline does.

A crash with a bot is DeepRacer's: the car's footprint corner inside the bot's footprint,
and only when the car ran into it from behind (the bot ahead of it along the track).
"""

from __future__ import annotations

import bisect
import math
from typing import Final

import numpy as np
from numpy.typing import NDArray

from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec
from sim.physics.objects.field import BOT_CAR_SHAPE, ObjectField
from sim.physics.objects.placement import CLEAR_BEFORE_LINE, Lanes
from sim.physics.objects.settings import BotSettings
from sim.tracks.track import Track

# A bot's look-ahead point, like a racecar's: its progress is measured there (simapp).
_FRONT: Final = 0.14
# The lanes are tabled this often along the centre line (metres): between two entries a
# lane bends by far less than a millimetre off the straight line between them.
_TABLE_SPACING: Final = 0.02


class _LaneTable:
    """Both lanes beside every point of the centre line, tabled densely: for a centre-line
    distance, each lane's point (x, y), its direction (cos, sin) and its signed offset from
    the centre line (positive to the left, driving along the track's rows). A step of a
    race then costs a lookup and a blend, not a projection."""

    def __init__(self, lanes: Lanes) -> None:
        centre = lanes.centre
        count = max(int(np.ceil(centre.total_length / _TABLE_SPACING)), len(centre.lengths))
        self.at = np.linspace(0.0, centre.total_length, count + 1)
        points = centre.point_at(self.at)
        tangent = centre.direction_at(self.at)
        columns = []
        for lane in (lanes.inner, lanes.outer):
            seg, t, foot = lane.project(points)
            direction = lane.direction_at(lane.arc_length(seg, t))
            rel = foot - points
            offset = tangent[:, 0] * rel[:, 1] - tangent[:, 1] * rel[:, 0]
            columns.append(np.column_stack([foot, direction, offset]))
        self.table = np.stack(columns, axis=1)  # (entries, lane, [x, y, cos, sin, offset])
        self._flat = self.table.reshape(len(self.at), 10)
        self._per_metre = np.append(1.0 / np.diff(self.at), 0.0)
        # The same as plain lists, for one car's bots stepped in plain floats.
        self.at_list: list[float] = self.at.tolist()
        self.rows: list[list[float]] = self._flat.tolist()

    def lookup(self, distance: FloatArray) -> FloatArray:
        """(..., 10) both lanes' entries (inner x, y, cos, sin, offset, then the outer's)
        at these centre-line distances, each in [0, the centre line's length)."""
        index = np.searchsorted(self.at, distance, side="right") - 1
        np.minimum(index, len(self.at) - 2, out=index)  # a distance rounded up to the length
        frac = ((distance - self.at[index]) * self._per_metre[index])[..., None]
        low = self._flat[index]
        return np.asarray(low + frac * (self._flat[index + 1] - low))


class BotField(ObjectField):
    """`settings`' bot cars for each of `cars` cars on `track`, placed from `seed`."""

    reports_heading = True

    def __init__(self, track: Track, settings: BotSettings, cars: int, *, seed: int = 0) -> None:
        super().__init__(track, settings.count, cars, BOT_CAR_SHAPE, seed=seed)
        self.settings = settings
        self.reported_speed = settings.speed
        self._table = _LaneTable(self.lanes)
        self._table_backwards: _LaneTable | None = None  # the reversed track's, when needed
        k = settings.count
        self.start = np.zeros((cars, k))  # centre-line distance at the episode's start
        self.outer = np.zeros((cars, k), dtype=bool)  # the lane it drives (or leaves)
        self.clock = np.zeros(cars)  # seconds the bots have driven this episode
        self.paused = np.zeros(cars)  # seconds they still stand still
        self.change_start = np.full((cars, k), np.inf)  # on the clock
        self.change_end = np.full((cars, k), np.inf)
        self._duration = (
            settings.lane_change_distance / settings.speed
            if settings.lane_change and settings.speed > 0.0
            else np.inf
        )
        for car in range(cars):
            self.draw(car)

    # --- episodes ------------------------------------------------------------------------
    def draw(self, car: int, backwards: bool = False) -> None:
        """Start `car`'s bots again for a new episode (placed anew every episode, as
        simapp does, which also restarts their lane-change timers); with `backwards` they
        drive the reversed track's lanes, the car's way round (simapp rebuilds its bots'
        lanes on the reversed track)."""
        if self._turn(car, backwards) and backwards and self._table_backwards is None:
            self._table_backwards = _LaneTable(self.lanes_of(car))
        s, k, rng = self.settings, self.count, self._rng
        end = self.length - CLEAR_BEFORE_LINE
        start = np.linspace(s.min_distance, end, k)
        if s.randomize:
            for i in rng.permutation(k):
                low = s.min_distance if i == 0 else start[i - 1] + s.min_distance
                high = end if i == k - 1 else start[i + 1] - s.min_distance
                if low < high:
                    start[i] = rng.uniform(low, high)
            self.outer[car] = rng.random(k) < 0.5
        else:
            self.outer[car] = np.arange(k) % 2 == 1
        self.start[car] = start
        self.clock[car] = 0.0
        self.paused[car] = 0.0
        # simapp: the first lane change is scheduled at the first step (its end time 0).
        first = 0.0 if np.isfinite(self._duration) else np.inf
        self.change_start[car] = first
        self.change_end[car] = first
        self._next_change_end = float(self.change_end[0].min()) if self.count else math.inf
        self.drawn[car] = True
        self._place(np.array([car]))

    def advance(self, seconds: float) -> None:
        if len(self.clock) == 1:
            self._advance_one(seconds)
            return
        moving = self.paused <= 0.0
        self.clock[moving] += seconds
        self.paused[~moving] -= seconds
        if np.isfinite(self._duration):
            self._schedule_lane_changes()
        self._place(np.arange(len(self.clock)))

    def _advance_one(self, seconds: float) -> None:
        """`advance` for a race's one car in plain floats (numpy's per-call costs on arrays
        of three bots were most of a race step's time)."""
        if self.paused[0] > 0.0:
            self.paused[0] -= seconds
        else:
            self.clock[0] += seconds
        clock = float(self.clock[0])
        if clock >= self._next_change_end:
            self._schedule_lane_changes()
        self._place_one(clock)

    def _place_one(self, clock: float) -> None:
        """`_place` for car 0 alone, bot by bot in plain floats; the same numbers."""
        self.placed += 1
        table = self._table_of(0)
        at, rows, length = table.at_list, table.rows, self.length
        last = len(at) - 2
        speed, across = self.settings.speed, self.settings.lane_change_distance
        starts, outer = self.start[0].tolist(), self.outer[0].tolist()
        begins, ends = self.change_start[0].tolist(), self.change_end[0].tolist()
        for i in range(self.count):
            d = (starts[i] + clock * speed) % length
            j = min(max(bisect.bisect_right(at, d) - 1, 0), last)
            frac = (d - at[j]) / (at[j + 1] - at[j])
            low, high = rows[j], rows[j + 1]
            h = 5 if outer[i] else 0
            o = 5 - h
            here = [low[h + c] + frac * (high[h + c] - low[h + c]) for c in range(5)]
            there = [low[o + c] + frac * (high[o + c] - low[o + c]) for c in range(5)]
            begin, end = begins[i], ends[i]
            u = 0.0
            if math.isfinite(end) and begin <= clock and end > begin:
                u = min(max((clock - begin) / (end - begin), 0.0), 1.0)
            blend = u * u * (3.0 - 2.0 * u)
            offset = here[4] + blend * (there[4] - here[4])
            slope = (there[4] - here[4]) * 6.0 * u * (1.0 - u) / across
            self.x[0, i] = here[0] + blend * (there[0] - here[0])
            self.y[0, i] = here[1] + blend * (there[1] - here[1])
            self.heading[0, i] = math.atan2(here[3], here[2]) + math.atan(slope)
            self.distance[0, i] = d
            self.from_centre[0, i] = abs(offset)
            self.left[0, i] = offset > 0.0

    def pass_time(self, car: int, seconds: float) -> None:
        """simapp's bots drive on while their car is held for a penalty (its crash into a
        bot included: only a bot's own crash into the car stops them)."""
        self.clock[car] += seconds
        if np.isfinite(self._duration):
            self._schedule_lane_changes()
        self._place(np.array([car]))

    def after_crash(self, cars: NDArray[np.bool_]) -> None:
        """A bot ran into these cars from behind: their bots stop for the penalty (simapp
        pauses the bots and shifts their lane changes by as much)."""
        hit = np.asarray(cars) & (self.paused <= 0.0)
        self.paused[hit] = self.settings.penalty_seconds

    def _schedule_lane_changes(self) -> None:
        """simapp's schedule: when a change has ended the bot is in the other lane, and the
        next change ends U(lower, upper) + its duration later."""
        due = self.clock[:, None] >= self.change_end
        if not due.any():
            return
        cars, bots = np.nonzero(due)
        done = self.change_end[cars, bots] > 0.0  # not the first, scheduling, one
        self.outer[cars[done], bots[done]] ^= True
        s = self.settings
        wait = self._rng.uniform(s.lower_lane_change_time, s.upper_lane_change_time, len(cars))
        end = self.clock[cars] + wait + self._duration
        self.change_end[cars, bots] = end
        self.change_start[cars, bots] = end - self._duration
        self._next_change_end = float(self.change_end[0].min())

    # --- where they are ------------------------------------------------------------------
    def _table_of(self, car: int) -> _LaneTable:
        if self.backwards[car]:
            assert self._table_backwards is not None
            return self._table_backwards
        return self._table

    def _centre_distance(self, cars: slice | NDArray[np.intp], clock: FloatArray) -> FloatArray:
        return np.asarray((self.start[cars] + clock * self.settings.speed) % self.length)

    def _place(self, cars: NDArray[np.intp]) -> None:
        """Put `cars`' bots where their clocks say: in their lane beside their centre-line
        point, or part of the way over to the other lane while they change."""
        self.placed += 1
        rows: slice | NDArray[np.intp] = slice(None) if len(cars) == len(self.clock) else cars
        clock = self.clock[rows][:, None]
        d = self._centre_distance(rows, clock)
        # (cars, bots, [inner x, y, cos, sin, offset, outer ...]), each car its way round.
        if not self.any_backwards:
            entries = self._table.lookup(d)
        else:
            assert self._table_backwards is not None
            backwards = self.backwards[rows]
            entries = np.empty((*d.shape, 10))
            entries[~backwards] = self._table.lookup(d[~backwards])
            entries[backwards] = self._table_backwards.lookup(d[backwards])
        outer = self.outer[rows][..., None]
        here = np.where(outer, entries[..., 5:], entries[..., :5])
        x, y, offset = here[..., 0], here[..., 1], here[..., 4]
        heading = np.arctan2(here[..., 3], here[..., 2])
        begin, end = self.change_start[rows], self.change_end[rows]
        changing = (clock >= begin) & (end > begin) & np.isfinite(end)
        if changing.any():
            there = np.where(outer, entries[..., :5], entries[..., 5:])
            with np.errstate(invalid="ignore", divide="ignore"):
                u = np.where(changing, np.clip((clock - begin) / (end - begin), 0.0, 1.0), 0.0)
            blend = u * u * (3.0 - 2.0 * u)
            x = x + blend * (there[..., 0] - x)
            y = y + blend * (there[..., 1] - y)
            across = there[..., 4] - offset
            offset = offset + blend * across
            # Moving across while moving along: the heading turns by the slope of the move
            # (its offset's change per metre along the lane).
            slope = across * 6.0 * u * (1.0 - u) / self.settings.lane_change_distance
            heading = heading + np.arctan(slope)
        self.x[rows], self.y[rows] = x, y
        self.heading[rows] = heading
        self.distance[rows] = d
        self.from_centre[rows] = np.abs(offset)
        self.left[rows] = offset > 0.0

    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        """Cars that ran into one of their bots from behind. A bot that runs into a car from
        behind is not the car's crash: the bots pause instead (simapp's `judge_action`)."""
        hits = self.hits(x, y, yaw, car_spec)
        if not hits.any():
            return np.zeros(len(x), dtype=bool)
        half = self.length / 2.0
        bot_front = self.distance + _FRONT
        mine = np.asarray(s, dtype=np.float64)
        if self.any_backwards:  # each car's distance its own way round, as its bots'
            mine = np.where(self.backwards, (self.length - mine) % self.length, mine)
        ahead = (bot_front - mine[:, None] + half) % self.length - half > 0.0
        crashed = (hits & ahead).any(axis=1)
        self.after_crash(np.asarray((hits & ~ahead).any(axis=1) & ~crashed))
        return np.asarray(crashed)

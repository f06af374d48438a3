"""The objects of a simulation, car by car, and what DeepRacer makes of them: crashes, what
sensors see and the reward `params`' object keys (docs/deepracer-objects.md). `ObjectField`
is what boxes and bot cars share; `ObstacleField` stands an object-avoidance race's boxes,
`sim.physics.objects.bots.BotField` drives a head-to-bot race's bot cars.

Each car of a simulation drives its own episode, so each has its own objects, placed again
when its episode starts. A crash is DeepRacer's: a corner of the car's footprint inside an
object's rectangle (for a box, the box and 0.1 m more), no distance threshold.

The params follow simapp's `get_object_reward_params`: objects in their own order (not
sorted), `objects_distance` in metres along the centre line from its first waypoint,
`closest_objects` the one behind and the one ahead of the car's look-ahead point along the
track (wrapping round the lap), both measured the car's own way round (a car driving
backwards this episode measures along the reversed lines, from their first point),
headings and speeds 0 for boxes (simapp fills them only with bot cars, and then gives every
object the bots' speed). `object_in_camera` says whether
the next object is inside the camera's field of view; simapp compares against the object
before it (an off-by-one in its camera check), which racer-tui does not copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec
from sim.physics.objects.placement import (
    BOT_CAR_HEIGHT,
    BOT_CAR_LENGTH,
    BOT_CAR_WIDTH,
    BOX_HEIGHT,
    BOX_LENGTH,
    BOX_MODEL_LENGTH,
    BOX_MODEL_WIDTH,
    BOX_WIDTH,
    Lanes,
    ObjectPose,
    obstacle_poses,
)
from sim.physics.objects.settings import Lane, ObstacleSettings
from sim.tracks.track import Track

# The DeepRacer camera's horizontal field of view and near plane (simapp `frustum.py`).
CAMERA_FIELD_OF_VIEW: Final = 1.13  # radians
CAMERA_NEAR: Final = 0.2  # metres
# A car starts in the other lane than a box this close along the track (simapp).
START_CLEARANCE: Final = 1.0
# After hitting a box a car is put back this far behind it, in the other lane; the box is
# the one nearest the car along the track, within CLOSEST_GAP (simapp RESET_BEHIND_DIST,
# CLOSEST_OBJ_GAP).
RESET_BEHIND: Final = 1.0
CLOSEST_GAP: Final = 1.0


@dataclass(frozen=True)
class ObjectShape:
    """An object's size: its crash rectangle (DeepRacer's, on the ground) and its body as
    the sensors see it (metres)."""

    crash_length: float  # along its heading
    crash_width: float
    length: float
    width: float
    height: float
    is_car: bool = False  # a bot car (the camera draws it darker than a box)

    def reach(self, car_spec: CarSpec) -> float:
        """How far apart a car's centre and this object's can be while touching: both
        half-diagonals (a quick test before `corners_inside`)."""
        car = math.hypot(car_spec.length / 2.0, car_spec.width / 2.0)
        return car + math.hypot(self.crash_length, self.crash_width) / 2


BOX_SHAPE: Final = ObjectShape(BOX_LENGTH, BOX_WIDTH, BOX_MODEL_LENGTH, BOX_MODEL_WIDTH, BOX_HEIGHT)
BOT_CAR_SHAPE: Final = ObjectShape(
    BOT_CAR_LENGTH, BOT_CAR_WIDTH, BOT_CAR_LENGTH, BOT_CAR_WIDTH, BOT_CAR_HEIGHT, is_car=True
)


Poses = tuple[FloatArray, FloatArray, FloatArray]  # x, y and heading (radians)


def corners_inside(
    car_spec: CarSpec, cars: Poses, shape: ObjectShape, objects: Poses
) -> NDArray[np.bool_]:
    """DeepRacer's crash test: (cars, objects), a corner of car i's footprint inside the
    crash rectangle of its object j. `cars` are (cars,) arrays, `objects` (cars, objects)
    ones: each car's own objects. Elementwise only, so a pair's answer is the same however
    many others are tested with it (a race's replay judges it so again)."""
    x, y, yaw = cars
    object_x, object_y, heading = objects
    half_l, half_w = car_spec.length / 2.0, car_spec.width / 2.0
    corners = np.array([[half_l, half_w], [half_l, -half_w], [-half_l, half_w], [-half_l, -half_w]])
    cos, sin = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    # (cars, 4) corner positions in the world.
    cx = x[:, None] + corners[:, 0] * cos - corners[:, 1] * sin
    cy = y[:, None] + corners[:, 0] * sin + corners[:, 1] * cos
    # Into each object's frame: (cars, objects, 4).
    dx = cx[:, None, :] - object_x[:, :, None]
    dy = cy[:, None, :] - object_y[:, :, None]
    bc, bs = np.cos(heading)[:, :, None], np.sin(heading)[:, :, None]
    along = dx * bc + dy * bs
    across = -dx * bs + dy * bc
    inside = (np.abs(along) <= shape.crash_length / 2.0) & (
        np.abs(across) <= shape.crash_width / 2.0
    )
    return np.asarray(inside.any(axis=2))


class ObjectField:
    """`count` objects of one `shape` for each of `cars` cars on `track`: where they are
    and what DeepRacer makes of them. Subclasses place them (`draw`) and move them."""

    #: What `objects_speed` reports for every object (simapp: the bots' speed, boxes too),
    #: and whether `objects_heading` is filled (only when there are bot cars).
    reported_speed: float = 0.0
    reports_heading: bool = False

    def __init__(
        self, track: Track, count: int, cars: int, shape: ObjectShape, *, seed: int = 0
    ) -> None:
        self.shape = shape
        self._track = track
        self.lanes = Lanes.of(track)
        self._lanes_backwards: Lanes | None = None  # built when a car first drives backwards
        # simapp: left of centre = inside the inner half of the road XOR the track turning
        # clockwise (the inner border is on the right then).
        self._inner_is_left = track.direction == "counter-clockwise"
        self.length = self.lanes.centre.total_length
        # Cars driving the track against its rows this episode (ALTERNATE_DRIVING_DIRECTION):
        # simapp reverses the track for the episode, so the car's objects stand, drive and
        # are measured along the reversed lines; distances, lanes and sides here are each
        # car's own way round.
        self.backwards = np.zeros(cars, dtype=bool)
        # Whether any car is: the per-step paths skip the reversed frame in one attribute
        # read while none is (every race, most trainings).
        self.any_backwards = False
        self.count = count
        self._rng = np.random.default_rng(seed)
        k = count
        self.x = np.zeros((cars, k))
        self.y = np.zeros((cars, k))
        self.heading = np.zeros((cars, k))  # radians
        self.distance = np.zeros((cars, k))  # metres along the centre line
        self.left = np.zeros((cars, k), dtype=bool)  # left of the centre line, driving on
        self.from_centre = np.zeros((cars, k))
        self.drawn = np.zeros(cars, dtype=bool)
        # Objects that stand still are handed to the camera as one Solids until they move
        # (it keeps its geometry between frames); `placed` counts the placings
        # (sim.sensors.objects_drawn keys its drawing on it).
        self.placed = 0

    # --- what subclasses do ------------------------------------------------------------
    def draw(self, car: int, backwards: bool = False) -> None:
        """Place `car`'s objects for its next episode, which it drives the track's way
        round or `backwards`."""
        raise NotImplementedError

    def advance(self, seconds: float) -> None:
        """Let every car's objects move on by one step of `seconds` (boxes stand still)."""

    def pass_time(self, car: int, seconds: float) -> None:
        """`car` is held for `seconds` (a penalty): its objects move on meanwhile."""

    def after_crash(self, cars: NDArray[np.bool_]) -> None:
        """Cars whose objects ran into them from behind this step (bots pause)."""

    def reset_behind(self, car: int, s: float) -> ObjectPose | None:
        """Where DeepRacer puts a car back after it crashed near distance `s`; None: where
        an off-track would."""
        return None

    # --- shared --------------------------------------------------------------------------
    def lanes_of(self, car: int) -> Lanes:
        """The lanes as `car` drives them this episode."""
        if not self.backwards[car]:
            return self.lanes
        if self._lanes_backwards is None:
            self._lanes_backwards = Lanes.of(self._track.reversed())
        return self._lanes_backwards

    def inner_is_left(self, car: int) -> bool:
        """Whether the inner lane is on `car`'s left this episode."""
        return self._inner_is_left != bool(self.backwards[car])

    def car_distance(self, car: int, s: float) -> float:
        """A centre-line distance along the track's rows as `car` measures it this episode
        (from the reversed line's first point when it drives backwards)."""
        return (self.length - s) % self.length if self.backwards[car] else s

    def _gap(self, car: int, i: int, distance: float) -> float:
        """How far object `i` of `car` is ahead of `distance` along the track (negative:
        behind), the shorter way round."""
        half = self.length / 2.0
        return float((self.distance[car, i] - distance + half) % self.length - half)

    def _turn(self, car: int, backwards: bool) -> bool:
        """Set `car`'s way round for its next episode; True when it changed."""
        changed = bool(self.backwards[car]) != backwards
        self.backwards[car] = backwards
        self.any_backwards = bool(self.backwards.any())
        return changed

    def _set(self, car: int, i: int, pose: ObjectPose) -> None:
        self.x[car, i], self.y[car, i] = pose.x, pose.y
        self.heading[car, i] = pose.heading
        self.distance[car, i] = pose.distance
        self.left[car, i] = (pose.lane is Lane.INNER) == self.inner_is_left(car)
        _, _, foot = self.lanes.centre.project(np.array([[pose.x, pose.y]]))
        self.from_centre[car, i] = math.hypot(pose.x - foot[0, 0], pose.y - foot[0, 1])

    def measure_where_they_stand(self) -> None:
        """Every object's distance along the centre line, side and distance from it, from
        where it stands: for cars that drive themselves (a race's rivals, a training's
        opponents), which no lane places. Left is left of the centre line driving the
        track's way (simapp: inside the inner half, flipped on a clockwise track, which is
        the same side)."""
        cars, count = self.x.shape
        points = np.column_stack([self.x.reshape(-1), self.y.reshape(-1)])
        centre = self.lanes.centre
        segment, t, foot = centre.project(points)
        relative = points - foot
        vectors = centre.vectors[segment]
        cross = vectors[:, 0] * relative[:, 1] - vectors[:, 1] * relative[:, 0]
        self.distance = centre.arc_length(segment, t).reshape(cars, count)
        self.left = (cross > 0.0).reshape(cars, count)
        self.from_centre = np.hypot(relative[:, 0], relative[:, 1]).reshape(cars, count)

    def start_pose(self, car: int, s: float) -> ObjectPose | None:
        """Where a car starting at centre-line distance `s` (along the track's rows) stands:
        in the other lane than an object of its within 1 m along the track (simapp's
        `_get_car_start_model_state`), facing its way round; None: on the centre line."""
        mine = self.car_distance(car, s)
        for i in range(self.count):
            if abs(self._gap(car, i, mine)) <= START_CLEARANCE:
                inner = self.left[car, i] == self.inner_is_left(car)
                return self.lanes_of(car).pose(mine, Lane.OUTER if inner else Lane.INNER)
        return None

    def hits(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        """(cars, objects): a corner of the car's footprint inside the object's crash
        rectangle."""
        # Nothing can touch unless the centres are within both half-diagonals: most steps
        # of a race end here, for a few numpy calls.
        reach = self.shape.reach(car_spec)
        if len(x) == 1:  # a race's one car: plain floats beat numpy's per-call costs
            cx, cy, limit = float(x[0]), float(y[0]), reach * reach
            if all(
                (cx - ox) ** 2 + (cy - oy) ** 2 > limit
                for ox, oy in zip(self.x[0].tolist(), self.y[0].tolist(), strict=True)
            ):
                return np.zeros((1, self.count), dtype=bool)
        else:
            near = (x[:, None] - self.x) ** 2 + (y[:, None] - self.y) ** 2 <= reach * reach
            close = np.flatnonzero(near.any(axis=1))
            if len(close) == 0:
                return near
            if len(close) < len(x):  # the full test only for the cars near an object
                hits = np.zeros_like(near)
                hits[close] = corners_inside(
                    car_spec,
                    (x[close], y[close], yaw[close]),
                    self.shape,
                    (self.x[close], self.y[close], self.heading[close]),
                )
                return hits
        return corners_inside(car_spec, (x, y, yaw), self.shape, (self.x, self.y, self.heading))

    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        """Cars that crashed into one of their objects (`s`: each car's look-ahead point's
        distance along the centre line). Hitting a box is always a crash."""
        if self.count == 0:
            return np.zeros(len(x), dtype=bool)
        return np.asarray(self.hits(x, y, yaw, car_spec).any(axis=1))

    def ray_distances(
        self,
        cars: NDArray[np.intp],
        x: FloatArray,
        y: FloatArray,
        yaw: FloatArray,
        *,
        angles: FloatArray,
        max_range: float,
    ) -> FloatArray:
        """(len(cars), rays) metres from each car's centre to the first of its objects
        along each ray (`angles` from the heading), `max_range` where none is that close:
        the objects as a lidar sees them, the slab test in each object's frame."""
        hit = np.full((len(cars), len(angles)), max_range)
        if self.count == 0:
            return hit
        # Only cars with an object within the lidar's reach need the rays: most have none.
        shape = self.shape
        reach = max_range + math.hypot(shape.length, shape.width) / 2.0
        x, y = np.asarray(x), np.asarray(y)
        near = (x[:, None] - self.x[cars]) ** 2 + (y[:, None] - self.y[cars]) ** 2 <= reach**2
        rows = np.flatnonzero(near.any(axis=1))
        if len(rows) == 0:
            return hit
        if len(rows) < len(cars):
            hit[rows] = self.ray_distances(
                np.asarray(cars)[rows],
                x[rows],
                y[rows],
                np.asarray(yaw)[rows],
                angles=angles,
                max_range=max_range,
            )
            return hit
        theta = np.asarray(yaw)[:, None] + np.asarray(angles)[None, :]  # (n, rays)
        dir_x, dir_y = np.cos(theta)[:, :, None], np.sin(theta)[:, :, None]
        bx, by, bh = (
            self.x[cars][:, None, :],
            self.y[cars][:, None, :],
            self.heading[cars][:, None, :],
        )
        cos, sin = np.cos(bh), np.sin(bh)
        ox = np.asarray(x)[:, None, None] - bx
        oy = np.asarray(y)[:, None, None] - by
        # The ray's origin and direction in the object's frame: (n, rays, objects).
        o_along, o_across = ox * cos + oy * sin, -ox * sin + oy * cos
        d_along, d_across = dir_x * cos + dir_y * sin, -dir_x * sin + dir_y * cos
        with np.errstate(divide="ignore", invalid="ignore"):
            near_a, far_a = _slab(o_along, d_along, self.shape.length / 2.0)
            near_c, far_c = _slab(o_across, d_across, self.shape.width / 2.0)
        enter = np.maximum(near_a, near_c)
        leave = np.minimum(far_a, far_c)
        seen = (enter <= leave) & (leave >= 0.0)
        distance = np.where(seen, np.maximum(enter, 0.0), np.inf).min(axis=2)
        return np.asarray(np.minimum(hit, distance))

    def all_params(
        self,
        ahead_s: list[float],
        ahead_x: list[float],
        ahead_y: list[float],
        heading_deg: list[float],
    ) -> list[dict[str, Any]]:
        """The object keys of every car's params (fresh lists each: a reward function may
        change them); per car, `ahead_s` is its look-ahead point's distance along the centre
        line, (`ahead_x`, `ahead_y`) the point, `heading_deg` its heading."""
        k = self.count
        if self.any_backwards:  # their look-ahead points' distances their own way round
            ahead_s = [self.car_distance(car, s) for car, s in enumerate(ahead_s)]
        xs, ys = self.x.tolist(), self.y.tolist()
        distances, left = self.distance.tolist(), self.left.tolist()
        from_centre = self.from_centre.tolist()
        headings = self.heading.tolist() if self.reports_heading else None
        out = []
        for car, d in enumerate(distances):
            order = sorted(range(k), key=d.__getitem__)
            s = ahead_s[car]
            next_index = next((i for i in order if d[i] > s), order[0])
            previous_index = order[order.index(next_index) - 1]
            x, y = xs[car], ys[car]
            out.append(
                {
                    "closest_objects": [previous_index, next_index],
                    "objects_location": [[a, b] for a, b in zip(x, y, strict=True)],
                    "objects_left_of_center": left[car],
                    "objects_speed": [self.reported_speed] * k,
                    "objects_heading": headings[car] if headings is not None else [0.0] * k,
                    "objects_distance": d,
                    "objects_distance_from_center": from_centre[car],
                    "object_in_camera": _in_camera(
                        x[next_index] - ahead_x[car], y[next_index] - ahead_y[car], heading_deg[car]
                    ),
                }
            )
        return out


class StandingField(ObjectField):
    """One car's objects standing where a training trace saw them (`sim.physics.objects.seen`): what
    the app's agent's-eye view draws for shuffled boxes and bot cars."""

    def __init__(self, track: Track, shape: ObjectShape, poses: FloatArray) -> None:
        """`poses` is (objects, 3): x, y and heading in radians."""
        poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        super().__init__(track, len(poses), 1, shape)
        self.x[0], self.y[0], self.heading[0] = poses[:, 0], poses[:, 1], poses[:, 2]
        self.drawn[0] = True
        self.placed = 1

    def draw(self, car: int, backwards: bool = False) -> None:
        """They stay where they were seen."""


class ObstacleField(ObjectField):
    """`settings`' boxes for each of `cars` cars on `track`, drawn from `seed`."""

    def __init__(
        self, track: Track, settings: ObstacleSettings, cars: int, *, seed: int = 0
    ) -> None:
        # IS_OBSTACLE_BOT_CAR parks bot cars where the boxes would stand.
        shape = BOT_CAR_SHAPE if settings.bot_car else BOX_SHAPE
        super().__init__(track, settings.boxes, cars, shape, seed=seed)
        self.settings = settings
        for car in range(cars):
            self.draw(car)

    def draw(self, car: int, backwards: bool = False) -> None:
        """The boxes of `car`'s next episode: the same ones unless the race randomises them
        (or the car turns round: they stand along its way round, as simapp places them on
        the reversed track)."""
        turned = self._turn(car, backwards)
        if self.drawn[car] and not self.settings.randomize and not turned:
            return
        lanes = self.lanes_of(car)
        for i, pose in enumerate(obstacle_poses(self.settings, lanes, self._rng)):
            self._set(car, i, pose)
        self.drawn[car] = True
        self.placed += 1

    def reset_behind(self, car: int, s: float) -> ObjectPose | None:
        """Where DeepRacer puts a car back after it hit a box: `RESET_BEHIND` metres behind
        the box nearest its centre-line distance `s` (within `CLOSEST_GAP`), in the other
        lane, facing along it (simapp's crash reset); None when no box is that close."""
        best, best_gap = None, CLOSEST_GAP
        mine = self.car_distance(car, s)
        for i in range(self.count):
            gap = self._gap(car, i, mine)
            if abs(gap) <= best_gap:
                best, best_gap = i, abs(gap)
        if best is None:
            return None
        inner = self.left[car, best] == self.inner_is_left(car)
        lane = Lane.OUTER if inner else Lane.INNER
        behind = (self.distance[car, best] - RESET_BEHIND) % self.length
        return self.lanes_of(car).pose(float(behind), lane)


def _in_camera(dx: float, dy: float, heading_deg: float) -> bool:
    """Whether a point (dx, dy) from the camera is inside DeepRacer's camera frustum, seen
    from a car heading `heading_deg`."""
    heading = math.radians(heading_deg)
    bearing = math.atan2(dy, dx) - heading
    bearing = math.atan2(math.sin(bearing), math.cos(bearing))
    forward = dx * math.cos(heading) + dy * math.sin(heading)
    return forward >= CAMERA_NEAR and abs(bearing) <= CAMERA_FIELD_OF_VIEW / 2.0


def _slab(origin: FloatArray, direction: FloatArray, half: float) -> tuple[FloatArray, FloatArray]:
    """Where a ray enters and leaves the slab |u| <= half (-inf, inf when it runs inside
    it, parallel; inf, -inf when it runs outside it, parallel)."""
    first = (-half - origin) / direction
    second = (half - origin) / direction
    near = np.minimum(first, second)
    far = np.maximum(first, second)
    parallel = direction == 0.0
    inside = np.abs(origin) <= half
    near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
    far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
    return np.asarray(near), np.asarray(far)

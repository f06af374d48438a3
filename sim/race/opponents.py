"""Opponents in a training: other racers' models on the track with the car being trained,
each driven by its own policy, so a racer can prepare for a bracket against a rival's
published model (docs/racers/head-to-head.md, "Training against an opponent").

Every car of a training fleet has opponents of its own, as it has bot cars of its own in a
head-to-bot training. For each opponent model one simulation drives that model's car in
every training car's world: N cars, and each step one forward pass of the model for all of
them. What each side sees and how a touch is judged are the head-to-head race's
(`sim.race.head_to_head`, docs/deepracer/head-to-head-simapp.md):
- the training car's camera and lidar see its opponents (the bot cars' rectangle, as simapp
  gives racing cars), and its reward params list them as objects, with their own speed and
  heading;
- each opponent's camera and lidar see its training car and that car's other opponents;
- a touch is the crash of the car behind: a training car that runs into an opponent ends
  its episode "crashed", as a crash into a bot car does; an opponent that runs into its
  training car from behind is held for the race's collision penalty where it stands, and a
  held opponent cannot be run into (simapp's blink);
- an opponent that leaves the track, or turns round, is put back as a race puts a car back
  and held for the off-track penalty; it laps on, whatever its training car does.
Each training episode starts on a head-to-head grid (0.75 m apart, alternate lanes): the
training car takes one of the grid's places, drawn from the seed, and its opponents the
others, so it learns to start behind them as well as ahead.

Where this departs from a race, and why: an opponent acts on what it sees after its
training car has moved in the step (a race's cars all act on the state before it), so that
one forward pass a step serves every car; 1/15 s, well below any driver's reaction.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.arrays import FloatArray
from sim.physics.car import CarSpec
from sim.physics.objects.field import ObjectField
from sim.physics.objects.rivals import RIVAL_SHAPE
from sim.physics.objects.settings import Lane
from sim.physics.resets import put_back
from sim.physics.simulation import TrackSimulation
from sim.race.driver import Driver
from sim.race.engine import RACE_EPISODE_RULES
from sim.race.head_to_head import GRID_GAP, MAX_CARS
from sim.race.rules import RaceRules

# A race's grid holds the training car and its opponents.
MOST_OPPONENTS = MAX_CARS - 1
# The penalties an opponent serves: the head-to-head race's own.
OPPONENT_RULES = RaceRules()
_PUT_BACK = (EpisodeStatus.OFF_TRACK, EpisodeStatus.REVERSED)


class _SeenByOpponents(ObjectField):
    """What one opponent model's cars see: in training car i's world, the training car and
    its other opponents (placed by `OpponentField`, never drawn here)."""

    def __init__(self, track: Any, cars: int, count: int) -> None:
        super().__init__(track, count, cars, RIVAL_SHAPE)

    def draw(self, car: int, backwards: bool = False) -> None:
        """Placed with the training car's episode (`OpponentField.draw`)."""

    def show(self, x: FloatArray, y: FloatArray, heading: FloatArray) -> None:
        self.x, self.y, self.heading = x, y, heading
        self.placed += 1  # the camera draws them anew

    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        # Touches are judged once, from the training car's side (`OpponentField.crashed`).
        return np.zeros(len(x), dtype=bool)


class OpponentField(ObjectField):
    """The opponents of every car of `training`, one car of each of `drivers` per training
    car; `seed` draws the grid places."""

    reports_heading = True

    def __init__(
        self,
        training: TrackSimulation,
        drivers: Sequence[Driver],
        *,
        seed: int = 0,
        rules: RaceRules = OPPONENT_RULES,
    ) -> None:
        count = len(drivers)
        if not 1 <= count <= MOST_OPPONENTS:
            raise ValueError(f"a training takes 1 to {MOST_OPPONENTS} opponents, not {count}")
        track, cars = training.track, training.n
        super().__init__(track, count, cars, RIVAL_SHAPE, seed=seed)
        self.training = training
        self.drivers = list(drivers)
        self.rules = rules
        # `training.track` is already the way the training drives it (REVERSE_DIR), so the
        # opponents drive the same lines forwards.
        self.sims = [
            TrackSimulation(track, cars, car=training.car, rules=RACE_EPISODE_RULES, seed=seed)
            for _ in drivers
        ]
        self._seen = [_SeenByOpponents(track, cars, count) for _ in drivers]
        for sim, seen, driver in zip(self.sims, self._seen, self.drivers, strict=True):
            sim.objects = seen
            driver.reset(sim)
        self.hold_left = np.zeros((cars, count))  # seconds each opponent still stands
        self._hold_pose = np.zeros((cars, count, 3))
        self._hold_travelled = np.zeros((cars, count))
        # Opponents that ran into their training car from behind: held from the next step.
        self._struck = np.zeros((cars, count), dtype=bool)
        self._measured = False
        # Grid places drawn for each opponent, not yet stood on: (car, x, y, heading).
        self._due: list[list[tuple[int, float, float, float]]] = [[] for _ in drivers]
        for car in range(cars):
            self.draw(car)
        self._stand_due()

    # --- episodes ------------------------------------------------------------------------
    def draw(self, car: int, backwards: bool = False) -> None:
        """Line `car`'s opponents up on a grid round where the training car starts its next
        episode, in the places it does not take."""
        if backwards:  # refused where a training is set up (`sim.training.opponents`)
            raise ValueError("opponents drive the track's way round only")
        training = self.training
        start = training.start_position(car, int(training.episode[car]))
        places = self.count + 1
        mine = int(self._rng.integers(places))
        front = start + mine * GRID_GAP
        others = [place for place in range(places) if place != mine]
        for k, place in enumerate(others):
            at = (front - place * GRID_GAP) % self.length
            pose = self.lanes.pose(at, Lane.OUTER if place % 2 == 0 else Lane.INNER)
            # Seen (and avoided by the training car's start) now; the opponent's own
            # simulation stands it there before it next drives, with every car drawn
            # meanwhile in one measuring pass (`_stand_due`).
            self._set(car, k, pose)
            self._due[k].append((car, pose.x, pose.y, pose.heading))
        self.hold_left[car] = 0.0
        self._struck[car] = False
        self.drawn[car] = True

    def _stand_due(self) -> None:
        """Stand the opponents drawn since the last step on their grid places, each
        starting its run from there."""
        if not any(self._due):
            return
        for sim, due in zip(self.sims, self._due, strict=True):
            if not due:
                continue
            cars = [car for car, *_ in due]
            sim.put_cars(cars, [(x, y, heading) for _, x, y, heading in due])
            for car in cars:
                sim.continue_episode(car, 0.0)
            due.clear()
        self._follow()

    def advance(self, seconds: float) -> None:
        """Every opponent drives one step on what it sees now, then serves its penalties."""
        self._stand_due()
        started_held = self.hold_left > 0.0
        for k, (sim, driver) in enumerate(zip(self.sims, self.drivers, strict=True)):
            action = driver.act(sim)
            held = started_held[:, k]
            steering = np.where(held, 0.0, action.steering_deg)
            speed = np.where(held, 0.0, action.speed)
            before_s, before_travelled = sim.s.copy(), sim.travelled.copy()
            before_x, before_y = sim.fleet.x.copy(), sim.fleet.y.copy()
            sim.apply(steering, speed)
            held_cars = np.flatnonzero(held).tolist()
            if held_cars:  # a held car stands where it stopped
                poses = [tuple(self._hold_pose[car, k].tolist()) for car in held_cars]
                sim.put_cars(held_cars, poses)
                for car in held_cars:
                    sim.continue_episode(car, float(self._hold_travelled[car, k]))
            for car in np.flatnonzero((sim.terminal != 0) & ~held).tolist():
                status = sim.status[car]
                travelled = float(sim.travelled[car])
                if status == EpisodeStatus.LAP_COMPLETE:
                    sim.continue_episode(car, travelled - self.length)
                elif status in _PUT_BACK:
                    put_back(
                        sim,
                        car,
                        s_ahead=float(before_s[car]),
                        car_x=float(before_x[car]),
                        car_y=float(before_y[car]),
                        travelled=float(before_travelled[car]),
                    )
                    self._hold(car, k, self.rules.penalty_seconds)
                else:  # nothing else is switched on for a racing car
                    sim.continue_episode(car, travelled)
        self.hold_left = np.maximum(self.hold_left - seconds, 0.0)
        for car, k in np.argwhere(self._struck & (self.hold_left <= 0.0)).tolist():
            self._hold(car, k, self.rules.collision_penalty_seconds)
        self._struck[:] = False
        self._follow()

    def _hold(self, car: int, k: int, seconds: float) -> None:
        if seconds <= 0.0:
            return
        fleet = self.sims[k].fleet
        self.hold_left[car, k] = seconds
        self._hold_pose[car, k] = (fleet.x[car], fleet.y[car], fleet.yaw[car])
        self._hold_travelled[car, k] = self.sims[k].travelled[car]

    def _follow(self) -> None:
        """The objects where the opponents are now, and each opponent's view of its world."""
        for k, sim in enumerate(self.sims):
            self.x[:, k], self.y[:, k], self.heading[:, k] = sim.fleet.x, sim.fleet.y, sim.fleet.yaw
        self.placed += 1
        self._measured = False
        training = self.training.fleet
        # Opponent k sees the training car first, then the other opponents in their order.
        for k, seen in enumerate(self._seen):
            others = [j for j in range(self.count) if j != k]
            seen.show(
                np.column_stack([training.x, self.x[:, others]]),
                np.column_stack([training.y, self.y[:, others]]),
                np.column_stack([training.yaw, self.heading[:, others]]),
            )

    # --- what the training car meets -----------------------------------------------------
    def crashed(
        self, x: FloatArray, y: FloatArray, yaw: FloatArray, s: FloatArray, car_spec: CarSpec
    ) -> NDArray[np.bool_]:
        """Training cars that ran into an opponent from behind; an opponent that ran into
        its training car from behind is held from the next step instead."""
        crashed = np.zeros(len(x), dtype=bool)
        hits = self.hits(x, y, yaw, car_spec) & (self.hold_left <= 0.0)
        if not hits.any():
            return crashed
        self._stand_due()  # "behind" is judged where they stand
        half = self.length / 2.0
        for car, k in np.argwhere(hits).tolist():
            ahead = (float(self.sims[k].s[car]) - float(s[car])) % self.length
            if 0.0 < ahead < half:
                crashed[car] = True
            else:
                self._struck[car, k] = True
        return crashed

    def speeds(self) -> FloatArray:
        """(cars, opponents): how fast each opponent drives now (0 while held)."""
        moving = np.column_stack([sim.fleet.speed for sim in self.sims])
        return np.where(self.hold_left > 0.0, 0.0, moving)

    def all_params(
        self,
        ahead_s: list[float],
        ahead_x: list[float],
        ahead_y: list[float],
        heading_deg: list[float],
    ) -> list[dict[str, Any]]:
        if not self._measured:  # only the reward params read it
            self.measure_where_they_stand()
            self._measured = True
        params = super().all_params(ahead_s, ahead_x, ahead_y, heading_deg)
        for car_params, speeds in zip(params, self.speeds().tolist(), strict=True):
            car_params["objects_speed"] = speeds  # each opponent's own, where bots share one
        return params

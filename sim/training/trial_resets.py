"""Resets inside evaluation trials: put back, penalised, and counted as DeepRacer does.

An evaluation trial survives up to `ResetRules.number_of_resets` off-tracks, crashes,
reversals and stops: each puts the car back (`sim.physics.resets.reset_pose`; after hitting one of
an object-avoidance race's boxes, 1 m behind it in the other lane) and adds its penalty to
the trial's clock, during which DeepRacer holds the car still (simapp
`rollout_agent_ctrl.py`, `_judge_action_at_run_phase`); the next one ends the trial. The
count is per trial, as simapp clears it at every episode start (`_clear_data`).
"""

from __future__ import annotations

import numpy as np

from sim.deepracer.vocabulary import EpisodeStatus
from sim.foundation.arrays import FloatArray
from sim.physics.car import STEP_SECONDS
from sim.physics.resets import MAX_RESETS, RESETTABLE, ResetRules, reset_pose
from sim.physics.simulation import TrackSimulation
from sim.tracks.track import Track

# Training's own evaluations end a trial at the first off-track, as DeepRacer training does
# (NUMBER_OF_RESETS 0 in simapp's rollout worker).
TRAINING_RESETS = ResetRules()
# A racer's evaluation drives every trial to the end of its lap or its time, off-tracks
# costing their penalty, as the DeepRacer console's evaluations do.
EVALUATION_RESETS = ResetRules(number_of_resets=MAX_RESETS)


class TrialResets:
    """The resets of trials driven side by side as the cars of one simulation."""

    def __init__(self, track: Track, trials: int, rules: ResetRules) -> None:
        self.track = track
        self.rules = rules
        self.penalty = np.zeros(trials)  # seconds of holds served, per trial
        self._resets: list[list[str]] = [[] for _ in range(trials)]
        self._s = self._travelled = self._x = self._y = np.zeros(trials)

    def before_step(self, sim: TrackSimulation) -> None:
        """Remember where every car was: a car that leaves goes back to that point."""
        if self.rules.number_of_resets == 0:
            return  # nothing is ever put back: no copies on the hot path
        self._s, self._travelled = sim.s.copy(), sim.travelled.copy()
        self._x, self._y = sim.fleet.x.copy(), sim.fleet.y.copy()

    def put_back(self, sim: TrackSimulation, car: int, status: str) -> bool:
        """Reset `car` after `status` if its trial still may; False when the trial ends."""
        resets = self._resets[car]
        if status not in RESETTABLE or len(resets) >= self.rules.number_of_resets:
            return False
        resets.append(str(status))
        held = self.rules.penalty(status)
        self.penalty[car] += held
        if sim.objects is not None:
            sim.objects.pass_time(car, held)  # bots drive on while the car is held
        s = float(self._s[car])
        behind = None
        if status == EpisodeStatus.CRASHED and sim.objects is not None:
            behind = sim.objects.reset_behind(car, float(sim.s[car]))
        if behind is not None:  # DeepRacer: behind the box it hit, in the other lane
            x, y, yaw = behind.x, behind.y, behind.heading
        else:
            x, y, yaw = reset_pose(self.track, s, float(self._x[car]), float(self._y[car]))
        sim.put(car, x, y, yaw, 0.0)
        length = self.track.length
        moved = (float(sim.s[car]) - s + length / 2.0) % length - length / 2.0
        sim.continue_episode(car, float(self._travelled[car]) + moved)
        return True

    def clock(self, sim: TrackSimulation) -> FloatArray:
        """Each trial's time so far: its driving steps and its penalty holds."""
        return np.asarray(sim.steps * STEP_SECONDS + self.penalty, dtype=np.float64)

    def resets(self, car: int) -> tuple[str, ...]:
        """The statuses that `car`'s trial was reset after, in order."""
        return tuple(self._resets[car])

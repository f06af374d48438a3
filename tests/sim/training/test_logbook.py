"""The training logbook: DeepRacer's TrainingMetrics and sim-trace, for every car that trains.

The cars drive at random in a real batched env, so episodes end in every way they can and
wheels leave the road one by one; the env tells the logbook of each step, as in training.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import read_training_metrics
from sim.env import BatchedDeepRacer, EnvConfig, StepInfo
from sim.physics.car import STEP_SECONDS
from sim.physics.simulation import TrackSimulation
from sim.tracks.catalog import resolve_track
from sim.training.logbook import TRACE_RULE, Logbook

PER_ITERATION = 5
DEEPRACER_STATUSES = {
    "prepare", "in_progress", "lap_complete", "off_track", "crashed", "reversed",
    "immobilized", "time_up", "pause", "park",
}  # fmt: skip


class Drive:
    """Cars of one batched env driving at random, watched as the logbook watches them."""

    def __init__(self, folder: Path, cars: int = 6, **budget: int) -> None:
        track = resolve_track("reinvent_base")
        self.space = discrete_grid()
        self.env = BatchedDeepRacer(EnvConfig(track, self.space), cars)
        self.logbook = Logbook(
            folder,
            cars=cars,
            episodes_per_iteration=PER_ITERATION,
            track_length=track.length,
            waypoints=track.center,
            discrete=True,
            **budget,
        )
        self.env.watcher = self.logbook  # as the trainer hooks it
        self.env.reset()
        self.rng = np.random.default_rng(3)

    def until(self, episodes: int) -> list[StepInfo]:
        finished: list[StepInfo] = []
        while self.logbook.episodes < episodes:
            actions = self.rng.integers(0, len(self.space.actions), self.env.n)
            _, _, terminated, truncated, infos = self.env.step(actions)
            finished += [infos[car] for car in np.flatnonzero(terminated | truncated)]
        self.logbook.flush()
        return finished


def _trace(folder: Path, iteration: int) -> list[dict[str, str]]:
    with (folder / "training-simtrace" / f"{iteration}-iteration.csv").open() as handle:
        return list(csv.DictReader(handle))


def test_every_episode_of_every_car_is_a_metrics_row_numbered_as_deepracer_does(
    tmp_path: Path,
) -> None:
    drive = Drive(tmp_path)
    finished = drive.until(23)
    rows = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json").episodes
    assert len(rows) == len(finished) >= 23
    assert [row.episode for row in rows] == list(range(1, len(rows) + 1))
    # DeepRacer's iterations: trial counts episodes within each of 5.
    assert [row.trial for row in rows] == [
        (n - 1) % PER_ITERATION + 1 for n in range(1, len(rows) + 1)
    ]
    assert [row.episode_status for row in rows] == [str(info.status) for info in finished]
    assert [row.elapsed_time_in_milliseconds for row in rows] == [
        round(info.steps * STEP_SECONDS * 1000) for info in finished
    ]
    # One simulated clock: an episode ends when its last step does, and lasts its steps.
    assert all(row.metric_time - row.start_time == row.elapsed_time_in_milliseconds for row in rows)
    assert [row.metric_time for row in rows] == sorted(row.metric_time for row in rows)
    assert {row.phase for row in rows} == {"training"}


def test_the_trace_has_every_step_of_every_car_as_simapp_writes_it(tmp_path: Path) -> None:
    drive = Drive(tmp_path)
    drive.until(12)
    metrics = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json")
    rows = [row for iteration in range(3) for row in _trace(tmp_path, iteration)]
    by_episode: dict[int, list[dict[str, str]]] = {}
    for row in rows:
        by_episode.setdefault(int(row["episode"]), []).append(row)
    assert sorted(by_episode) == list(range(len(metrics.episodes)))  # from 0, as simapp
    for number, steps in by_episode.items():
        episode = metrics.episodes[number]
        assert [float(row["steps"]) for row in steps] == list(range(1, len(steps) + 1))
        assert round(len(steps) * STEP_SECONDS * 1000) == episode.elapsed_time_in_milliseconds
        stamps = np.array([float(row["tstamp"]) for row in steps])
        assert np.allclose(np.diff(stamps), STEP_SECONDS, atol=0.0011)  # the clock advances
        assert stamps[-1] == pytest.approx(episode.metric_time / 1000, abs=0.001)
        assert steps[0]["episode_status"] == "prepare"
        assert [row["done"] for row in steps] == ["False"] * (len(steps) - 1) + ["True"]
        assert steps[-1]["episode_status"] == episode.episode_status.lower().replace(" ", "_")
        assert {row["episode_status"] for row in steps} <= DEEPRACER_STATUSES
    # The step's own action, never the restart's: every row drives one of the actions.
    actions = {(a.steering_angle, a.speed) for a in drive.space.actions}
    for row in rows:
        action = drive.space.actions[int(row["action"])]
        assert (float(row["steer"]), float(row["throttle"])) == (
            action.steering_angle,
            action.speed,
        )
        assert (float(row["steer"]), float(row["throttle"])) in actions
    # all_wheels_on_track is all four wheels on the road: False as soon as one is off, so
    # also on steps that went on (off track is all four off).
    partly_off = [row for row in rows if row["all_wheels_on_track"] == "False"]
    assert any(row["episode_status"] == "in_progress" for row in partly_off)
    off_track = [row for row in rows if row["episode_status"] == "off_track"]
    assert off_track and all(row["all_wheels_on_track"] == "False" for row in off_track)


class PoseWatcher:
    """Notes where each car is before and after every step, then tells the logbook."""

    def __init__(self, logbook: Logbook) -> None:
        self.logbook = logbook
        self.steps: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # before, after, done

    def before_step(self, sim: TrackSimulation) -> None:
        self._before = sim.ahead.copy()
        self.logbook.before_step(sim)

    def after_step(self, sim: TrackSimulation, actions: np.ndarray, rewards: np.ndarray) -> None:
        self.steps.append((self._before, sim.ahead.copy(), sim.done.copy()))
        self.logbook.after_step(sim, actions, rewards)


def test_the_trace_follows_deepracers_row_timing(tmp_path: Path) -> None:
    # DeepRacer's rows show the pose one row late (row i+1 at the state of row i's tstamp):
    # each row where its command was sent from, the episode's last row where it ended.
    drive = Drive(tmp_path, cars=3)
    watcher = PoseWatcher(drive.logbook)
    drive.env.watcher = watcher
    drive.until(6)
    expected: dict[int, list[tuple[float, float]]] = {0: [], 1: [], 2: []}
    episodes: list[list[tuple[float, float]]] = []
    for before, after, done in watcher.steps:
        for car in range(3):
            if done[car]:
                episodes.append([*expected[car], tuple(after[car])])
                expected[car] = []
            else:
                expected[car].append(tuple(before[car]))
    metrics = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json").episodes
    by_episode: dict[int, list[tuple[float, float]]] = {}
    for row in _trace(tmp_path, 0) + _trace(tmp_path, 1):
        by_episode.setdefault(int(row["episode"]), []).append((float(row["X"]), float(row["Y"])))
    assert len(by_episode) == len(metrics) == len(episodes)
    for number, poses in by_episode.items():
        assert np.allclose(poses, episodes[number], atol=1e-3)  # the trace has 4 decimals


def test_a_sample_is_whole_iterations_and_counted_in_the_metrics(tmp_path: Path) -> None:
    drive = Drive(tmp_path, trace_base_bytes=0, trace_bytes_per_minute=0)
    drive.until(17)
    traced = sorted(path.name for path in (tmp_path / "training-simtrace").iterdir())
    assert traced == ["0-iteration.csv"]  # iteration 0 always: deepracer-utils counts from it
    rows = _trace(tmp_path, 0)
    assert sorted({int(row["episode"]) for row in rows}) == list(range(PER_ITERATION))
    data = json.loads((tmp_path / "metrics" / "TrainingMetrics.json").read_text())
    assert data["sim_trace"] == {
        "episodes": len(data["metrics"]),
        "traced_episodes": PER_ITERATION,
        "traced_steps": len(rows),
        "rule": TRACE_RULE,
    }


def test_a_second_run_continues_the_numbering_the_clock_and_the_trace(tmp_path: Path) -> None:
    first = Drive(tmp_path)
    first.until(7)
    before = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json").episodes
    path = tmp_path / "training-simtrace" / "1-iteration.csv"
    with path.open("a") as handle:
        handle.write("9,1.0,0.5")  # a run killed while appending leaves a line cut short
    second = Drive(tmp_path)
    assert (second.logbook.episodes, second.logbook.clock) == (
        len(before),
        before[-1].metric_time / 1000,
    )
    second.until(len(before) + 6)
    after = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json").episodes
    assert after[: len(before)] == before
    assert [row.episode for row in after] == list(range(1, len(after) + 1))
    assert min(row.metric_time for row in after[len(before) :]) > before[-1].metric_time
    episodes = [int(row["episode"]) for i in range(3) for row in _trace(tmp_path, i)]
    assert sorted(set(episodes)) == list(range(len(after)))
    assert not path.read_text().endswith("0.5")


def test_evaluations_during_training_keep_the_last_episode_and_trial(tmp_path: Path) -> None:
    drive = Drive(tmp_path)
    drive.until(7)
    episodes = drive.logbook.episodes
    drive.logbook.add_evaluation([(8.5, 100.0, "Lap complete"), (2.0, 20.0, "Off track")])
    drive.logbook.flush()
    rows = read_training_metrics(tmp_path / "metrics" / "TrainingMetrics.json").episodes
    evaluation = [row for row in rows if row.phase == "evaluation"]
    assert [(row.episode, row.trial) for row in evaluation] == [
        (episodes, (episodes - 1) % PER_ITERATION + 1)
    ] * 2
    assert [row.elapsed_time_in_milliseconds for row in evaluation] == [8500, 2000]
    assert evaluation[1].start_time == evaluation[0].metric_time  # one after the other

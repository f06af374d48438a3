"""deepracer-utils, the community's log analysis, reads a model racer-tui trained and
evaluated, unchanged: the folder is a deepracer-for-cloud model folder.

One short real training (a few seconds: four cars, small rollouts, iterations of five
episodes) and two evaluations, shared by the tests of this module.
"""

from __future__ import annotations

import json
from collections.abc import Iterator

import numpy as np
import pytest
from deepracer.logs import AnalysisUtils, DeepRacerLog
from deepracer.logs.metrics import TrainingMetrics
from deepracer.logs.misc import LogFolderType

from sim.deepracer.files import read_evaluation_metrics, read_training_metrics
from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from sim.physics.car import STEP_SECONDS
from sim.physics.simulation import TrackSimulation
from sim.race.driver import DriverAction, reference_driver
from sim.training import events
from sim.training.evaluation import evaluate_model
from sim.training.trainer import RunOptions, Trainer
from tests.sim.race.drivers import ScriptedDriver

PER_ITERATION = 5
TINY = RunOptions(minutes=5, cars=4, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)
SIMAPP_STATUSES = {
    "prepare", "in_progress", "lap_complete", "off_track", "crashed", "reversed",
    "immobilized", "time_up", "pause", "park",
}  # fmt: skip


class SteadyReference:
    """The reference driver held to 2 m/s: laps of about ten seconds on re:Invent 2018."""

    name = "steady"
    content_hash = "steady"

    def reset(self, sim: TrackSimulation) -> None:
        self._driver = reference_driver(sim.track)
        self._driver.reset(sim)

    def act(self, sim: TrackSimulation) -> DriverAction:
        action = self._driver.act(sim)
        return DriverAction(action.steering_deg, np.minimum(action.speed, 2.0), action.action_index)


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ModelFolder]:
    """A model trained for three iterations and more, then evaluated twice: by its policy,
    and by a steady reference driver that completes its laps."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RACER_TUI_HOME", str(tmp_path_factory.mktemp("home")))
        folder = new_model(
            "analysed", hyperparameters={"num_episodes_between_training": PER_ITERATION}
        )
        stream: list[events.Event] = []

        def enough() -> bool:
            updates = [e for e in stream if isinstance(e, events.Update)]
            return bool(updates) and updates[-1].episodes >= 3 * PER_ITERATION + 2

        stream.append(Trainer(folder, stream.append, enough, TINY).run())
        evaluate_model(folder, trials=3)
        evaluate_model(folder, trials=3, driver=SteadyReference())
        yield folder


def test_deepracer_log_loads_the_training_trace_of_every_car(trained: ModelFolder) -> None:
    log = DeepRacerLog(str(trained.path))
    assert log.fh.type is LogFolderType.DRFC_MODEL_SINGLE_WORKERS
    log.load()
    df = log.dataframe()
    metrics = read_training_metrics(trained.training_metrics_file)
    training = [row for row in metrics.episodes if row.phase == "training"]
    assert metrics.sim_trace is not None
    assert metrics.sim_trace.traced_episodes == len(training)  # a short run traces it all
    assert len(df) == metrics.sim_trace.traced_steps
    # Every episode of every car, numbered as the metrics number them (from 0, as simapp).
    assert sorted(set(df["unique_episode"])) == list(range(len(training)))
    assert set(df["iteration"]) == set(range((len(training) - 1) // PER_ITERATION + 1))
    assert log.hyperparameters()["num_episodes_between_training"] == PER_ITERATION
    assert log.action_space() == trained.metadata().action_space.to_metadata()


def test_the_rows_are_the_steps_as_simapp_writes_them(trained: ModelFolder) -> None:
    log = DeepRacerLog(str(trained.path))
    log.load()
    df = log.dataframe()
    training = [
        row
        for row in read_training_metrics(trained.training_metrics_file).episodes
        if row.phase == "training"
    ]
    space = trained.metadata().action_space
    for number, steps in df.groupby("unique_episode"):
        episode = training[int(number)]
        assert list(steps["steps"]) == list(range(1, len(steps) + 1))
        assert round(len(steps) * STEP_SECONDS * 1000) == episode.elapsed_time_in_milliseconds
        # tstamp advances by the simulated time of each step.
        assert np.allclose(np.diff(steps["tstamp"]), STEP_SECONDS, atol=0.0011)
        statuses = list(steps["episode_status"])
        assert statuses[0] == "prepare"
        assert list(steps["done"]) == [False] * (len(steps) - 1) + [True]
        final = statuses[-1]
        assert final == episode.episode_status.lower().replace(" ", "_")
    assert set(df["episode_status"]) <= SIMAPP_STATUSES
    # Each row drives its own step's action (a car's restart would show 0 m/s).
    for action, steer, speed in zip(df["action"], df["steering_angle"], df["speed"], strict=True):
        chosen = space.actions[int(action)]
        assert (steer, speed) == (chosen.steering_angle, chosen.speed)
    assert not df.loc[df["episode_status"] == "off_track", "on_track"].any()
    assert df["tstamp"].nunique() > len(df) / TINY.cars / 2  # one clock, advancing


def test_training_metrics_are_read_per_iteration_as_deepracer_writes_them(
    trained: ModelFolder,
) -> None:
    metrics = TrainingMetrics(None, fname=str(trained.training_metrics_file)).metrics
    training = metrics[metrics["phase"] == "training"]
    assert list(training["episode"]) == list(range(1, len(training) + 1))
    per_iteration = training.groupby("iteration").size()
    complete = len(training) // PER_ITERATION
    assert list(per_iteration)[:complete] == [PER_ITERATION] * complete
    assert set(training["trial"]) == set(range(1, PER_ITERATION + 1))
    evaluation = metrics[metrics["phase"] == "evaluation"]
    assert len(evaluation) > 0
    # An evaluation belongs to the iteration of the training episode it followed.
    for _, row in evaluation.iterrows():
        assert row["iteration"] == (row["episode"] - 1) // PER_ITERATION


def test_lap_times_from_the_evaluation_trace_agree_with_the_evaluation_metrics(
    trained: ModelFolder,
) -> None:
    log = DeepRacerLog(str(trained.path))
    log.load_evaluation_trace()
    laps = AnalysisUtils.simulation_agg(log.dataframe(), "stream", "episode", is_eval=True)
    files = trained.evaluation_files()
    assert sorted(set(laps["stream"])) == [
        path.name.removeprefix("EvaluationMetrics-").removesuffix(".json") for path in files
    ]
    compared = 0
    for path in files:
        stamp = path.name.removeprefix("EvaluationMetrics-").removesuffix(".json")
        trials = read_evaluation_metrics(path)
        mine = laps[laps["stream"] == stamp].sort_values("episode")
        assert len(mine) == len(trials)
        for (_, lap), trial in zip(mine.iterrows(), trials, strict=True):
            if trial.lap_time_seconds is None:
                continue
            assert lap["progress"] == 100
            assert lap["time"] == pytest.approx(trial.lap_time_seconds, rel=0.01)
            compared += 1
    assert compared >= 3  # the steady driver's laps at least


def test_the_folder_keeps_the_drfc_names(trained: ModelFolder) -> None:
    names = {path.relative_to(trained.path).as_posix() for path in trained.path.rglob("*")}
    assert {"model/model_metadata.json", "ip/hyperparameters.json"} <= names
    assert {"metrics/TrainingMetrics.json", "training-simtrace/0-iteration.csv"} <= names
    for path in trained.evaluation_files():
        stamp = path.name.removeprefix("EvaluationMetrics-").removesuffix(".json")
        assert f"evaluation-{stamp}/evaluation-simtrace/0-iteration.csv" in names
    # racer-tui's own files beside them.
    assert {"policy.safetensors", "training-state.json", "reward_function.py"} <= names
    assert json.loads(trained.training_state_file.read_text())["state"] == "stopped"


def test_an_off_track_in_an_evaluation_holds_the_trace_clock_for_its_penalty() -> None:
    folder = new_model("swerver")
    track = folder.track()
    report = evaluate_model(folder, trials=1, driver=ScriptedDriver(track, swerve_at=(60,)))
    assert report.metrics_file is not None
    (trial,) = read_evaluation_metrics(report.metrics_file)
    assert trial.off_track_count == 1 and trial.lap_time_seconds is not None
    log = DeepRacerLog(str(folder.path))
    log.load_evaluation_trace()
    df = log.dataframe()
    off = df.index[df["episode_status"] == "off_track"]
    assert len(off) == 1  # simapp's off_track row, then the car goes on
    assert df.loc[off[0], "pause_duration"] == 2.0
    held = df.loc[off[0] + 1, "tstamp"] - df.loc[off[0], "tstamp"]
    assert held == pytest.approx(2.0 + STEP_SECONDS, abs=0.002)
    (lap,) = AnalysisUtils.simulation_agg(df, "stream", "episode", is_eval=True)["time"]
    assert lap == pytest.approx(trial.lap_time_seconds, rel=0.01)  # the penalty included

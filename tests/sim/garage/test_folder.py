"""Model folders: DeepRacer files on disk, created whole, with a status a racer can trust."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from sim.deepracer.files import (
    read_hyperparameters,
    read_model_metadata,
    read_training_params,
)
from sim.garage.folder import (
    ModelError,
    ModelFolder,
    ModelStatus,
    create_model,
    delete_model,
    list_models,
    model_content_hash,
    models_dir,
    open_model,
)
from sim.garage.options import default_model_spec, new_model
from sim.reward.errors import RewardFunctionError
from sim.tracks.catalog import resolve_track
from sim.training.config import model_env_config
from tests.sim.garage.helpers import add_evaluation, add_policy, write_training_state


def test_a_new_model_is_a_folder_of_deepracer_files(model: ModelFolder, racer_home: Path) -> None:
    assert model.path == racer_home / "models" / "rookie"
    assert model.name == "rookie"
    files = {path.relative_to(model.path).as_posix() for path in model.path.rglob("*.*")}
    # deepracer-for-cloud's model folder, reward function and training params at the top.
    assert files == {
        "model/model_metadata.json",
        "ip/hyperparameters.json",
        "training_params.yaml",
        "reward_function.py",
    }
    metadata = read_model_metadata(model.metadata_file)
    assert metadata.action_space.kind == "discrete"
    assert metadata.sensors == ("vector",)
    assert json.loads(model.metadata_file.read_text())["action_space_type"] == "discrete"
    assert read_hyperparameters(model.hyperparameters_file)["loss_type"] == "huber"
    params = read_training_params(model.training_params_file)
    assert params.world_name == "reinvent_base"
    assert params.max_minutes == 60.0
    assert params.track_hash == resolve_track("re:Invent 2018").content_hash
    assert "def reward_function(params)" in model.reward_source()


def test_the_folder_knows_where_the_trainer_writes(model: ModelFolder) -> None:
    assert model.policy_file.name == "policy.safetensors"
    assert model.checkpoints_dir.name == "checkpoints"
    assert model.training_state_file.name == "training-state.json"
    # DeepRacer's logs where deepracer-for-cloud writes them.
    assert model.training_trace_dir == model.path / "training-simtrace"
    assert model.training_metrics_file == model.path / "metrics" / "TrainingMetrics.json"
    stamp = "20250101120000"
    assert model.evaluation_metrics_file(stamp) == (
        model.path / "metrics" / "EvaluationMetrics-20250101120000.json"
    )
    assert model.evaluation_trace_file(stamp) == (
        model.path / "evaluation-20250101120000" / "evaluation-simtrace" / "0-iteration.csv"
    )


def test_env_config_is_what_training_runs(model: ModelFolder) -> None:
    config = model_env_config(model)
    assert config.track.name == "reinvent_base"
    assert config.sensors == ("vector",)
    assert config.action_space == model.metadata().action_space
    assert config.reward is not None


def test_status_follows_the_models_life(model: ModelFolder) -> None:
    assert model.status() is ModelStatus.UNTRAINED
    write_training_state(model, "running")  # this test process stands in for the trainer
    assert model.status() is ModelStatus.TRAINING
    add_policy(model)
    assert model.status() is ModelStatus.TRAINING
    write_training_state(model, "finished")  # at 12:05
    assert model.status() is ModelStatus.TRAINED
    add_evaluation(model, stamp="20250101121000")
    assert model.status() is ModelStatus.EVALUATED
    # Trained again since: its laps are not its policy's, so it is trained, not evaluated.
    state = json.loads(model.training_state_file.read_text())
    state["updated_at"] = "2025-01-01T12:20:00+00:00"
    model.training_state_file.write_text(json.dumps(state))
    assert model.status() is ModelStatus.TRAINED


def test_a_trainer_that_died_is_not_training(model: ModelFolder) -> None:
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        text=True,
        capture_output=True,
        check=True,
    )
    write_training_state(model, "running", pid=int(dead.stdout))
    assert not model.is_training()
    assert model.status() is ModelStatus.UNTRAINED


def test_junk_training_state_is_ignored(model: ModelFolder) -> None:
    model.training_state_file.write_text("{not json")
    assert model.training_state() is None
    model.training_state_file.write_text('{"state": "running", "pid": true}')
    assert not model.is_training()


def test_content_hash_identifies_metadata_and_weights(model: ModelFolder) -> None:
    untrained = model.content_hash()
    policy = add_policy(model, seed=1)
    trained = model.content_hash()
    assert trained != untrained
    assert trained == model_content_hash(model.metadata(), policy)
    add_policy(model, seed=2)
    assert model.content_hash() != trained


def test_evaluations_are_listed_oldest_first(model: ModelFolder) -> None:
    add_evaluation(model, "20250102000000", lap_ms=9000)
    add_evaluation(model, "20250101000000", lap_ms=9900)
    assert [p.name for p in model.evaluation_files()] == [
        "EvaluationMetrics-20250101000000.json",
        "EvaluationMetrics-20250102000000.json",
    ]
    assert model.best_evaluation_lap() == 9.0
    latest = model.latest_evaluation()
    assert latest is not None and latest[0].elapsed_time_in_milliseconds == 9000


def test_open_model_by_name_or_path(model: ModelFolder) -> None:
    assert open_model("rookie") == model
    assert open_model(str(model.path)) == model
    with pytest.raises(ModelError, match=r"no model named 'nobody'.*model list"):
        open_model("nobody")


def test_list_models_skips_leftovers(model: ModelFolder) -> None:
    new_model("Alpha")
    (models_dir() / ".half.tmp").mkdir()
    (models_dir() / "not-a-model").mkdir()
    (models_dir() / "stray.txt").write_text("x")
    assert [m.name for m in list_models()] == ["Alpha", "rookie"]


@pytest.mark.parametrize("name", ["", "a b", "../up", "x" * 65, "dot.name"])
def test_bad_names_are_refused(name: str) -> None:
    with pytest.raises(ModelError, match="cannot be a model name; use letters"):
        new_model(name)


def test_names_are_unique_without_case(model: ModelFolder) -> None:
    with pytest.raises(ModelError, match="'rookie' already exists"):
        new_model("ROOKIE")


def test_creation_is_all_or_nothing(racer_home: Path) -> None:
    spec = default_model_spec()

    def fail(folder: ModelFolder) -> None:
        (folder.path / "policy.safetensors").write_bytes(b"partial")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        create_model(
            "crashy",
            track=spec.track,
            metadata=spec.metadata,
            hyperparameters={},
            reward_source=spec.reward_source,
            populate=fail,
        )
    assert list(models_dir().iterdir()) == []


def test_nothing_is_written_for_a_broken_reward_function() -> None:
    spec = default_model_spec()
    with pytest.raises(RewardFunctionError):
        create_model(
            "broken",
            track=spec.track,
            metadata=spec.metadata,
            hyperparameters={},
            reward_source="def reward_function(params):\n    return (\n",
        )
    assert list(models_dir().iterdir()) == []


def test_hyperparameters_out_of_range_name_the_range() -> None:
    spec = default_model_spec()
    with pytest.raises(ModelError, match="batch_size must be a whole number from 32 to 512"):
        create_model(
            "big",
            track=spec.track,
            metadata=spec.metadata,
            hyperparameters={"batch_size": 1024},
            reward_source=spec.reward_source,
        )


def test_a_track_file_must_be_imported_first(deepracer_dir: Path) -> None:
    with pytest.raises(ModelError, match="tracks import FILE"):
        new_model("npy", track=str(deepracer_dir / "tracks" / "Oval_track.npy"))


def test_a_missing_track_is_reported_with_the_model(model: ModelFolder) -> None:
    params = model.training_params_file
    params.write_text(params.read_text().replace("reinvent_base", "gone-track"))
    with pytest.raises(ModelError, match="model 'rookie' trains on track 'gone-track'"):
        model.track()


def test_a_damaged_file_is_named(model: ModelFolder) -> None:
    model.metadata_file.write_text("[1, 2")
    with pytest.raises(ModelError, match=r"model_metadata\.json: not valid JSON"):
        model.metadata()


def test_delete_refuses_while_training(model: ModelFolder) -> None:
    write_training_state(model, "running")
    with pytest.raises(ModelError, match="is training right now"):
        delete_model(model)
    write_training_state(model, "stopped")
    delete_model(model)
    assert not model.path.exists()
    assert list(models_dir().iterdir()) == []

"""Importing DeepRacer model folders as community tools write them, starting with a real one."""

from __future__ import annotations

import json
import pickle
import shutil
from pathlib import Path

import pytest
from deepracer.logs import AnalysisUtils, DeepRacerLog
from deepracer.logs.metrics import TrainingMetrics

from sim.coach.reward_line import template_source
from sim.deepracer.files import read_evaluation_metrics, read_training_metrics
from sim.foundation.remedies import Fix, Note
from sim.garage.bundle import BundleError
from sim.garage.deepracer_import import import_deepracer_folder
from sim.garage.folder import ModelError, ModelFolder, ModelStatus, models_dir
from sim.garage.importing import import_model
from sim.garage.options import DEFAULT_TRACK
from sim.garage.summary import training_summary
from sim.reward.errors import RewardFunctionError


@pytest.fixture
def drfc_copy(deepracer_dir: Path, tmp_path: Path) -> Path:
    """A writable copy of the shared DeepRacer-for-Cloud folder, to break on purpose."""
    copy = tmp_path / "drfc-copy"
    shutil.copytree(deepracer_dir / "drfc-model", copy)
    for path in [copy, *copy.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    return copy


def test_the_real_drfc_model_imports(deepracer_dir: Path) -> None:
    result = import_model(deepracer_dir / "drfc-model")
    folder = result.folder
    assert folder.name == "drfc-model"
    metadata = folder.metadata()
    assert metadata.sensors == ("camera",)
    assert len(metadata.action_space.actions) == 14
    assert metadata.version == "4"
    hyperparameters = folder.hyperparameters()
    assert hyperparameters["discount_factor"] == 0.95
    assert hyperparameters["num_epochs"] == 3
    # It has no reward function and no known track: filled in, and said so.
    assert folder.reward_source() == template_source("follow_center_line")
    assert folder.training_params().world_name == DEFAULT_TRACK
    notes = " ".join(result.notes)
    assert "no reward_function.py: the follow_center_line template is used" in notes
    assert f"set up on {DEFAULT_TRACK}; choose another with --track" in notes
    assert "starts untrained" in notes
    assert folder.status() is ModelStatus.UNTRAINED


def test_its_metrics_come_along_in_our_form(deepracer_dir: Path) -> None:
    folder = import_model(deepracer_dir / "drfc-model").folder
    source = read_training_metrics(
        deepracer_dir / "drfc-model" / "metrics" / "TrainingMetrics.json"
    )
    copied = read_training_metrics(folder.training_metrics_file)
    assert copied == source
    assert len(copied.episodes) == 600
    names = [path.name for path in folder.evaluation_files()]
    assert names == [
        "EvaluationMetrics-20220709200242.json",
        "EvaluationMetrics-20220709200509.json",
        "EvaluationMetrics-20220709200711.json",
    ]
    original = read_evaluation_metrics(
        deepracer_dir / "drfc-model" / "metrics" / "EvaluationMetrics-20220709200242.json"
    )
    assert read_evaluation_metrics(folder.evaluation_files()[0]) == original
    assert folder.best_evaluation_lap() == pytest.approx(13.392)


def test_track_and_name_can_be_chosen(deepracer_dir: Path) -> None:
    result = import_model(deepracer_dir / "drfc-model", name="borrowed", track="speedway")
    assert result.folder.name == "borrowed"
    assert result.folder.track().name == "speedway"
    assert not any("--track" in note for note in result.notes)


def test_a_reward_function_in_the_folder_is_used(drfc_copy: Path) -> None:
    source = (
        "def reward_function(params):\n    return 1.0 if params['all_wheels_on_track'] else 1e-3\n"
    )
    (drfc_copy / "reward_function.py").write_text(source)
    result = import_deepracer_folder(drfc_copy, name="own-reward")
    assert result.folder.reward_source() == source
    notes = " ".join(result.notes)
    assert "template" not in notes
    assert "reward_function.py was checked but not run: it runs, contained" in notes


def test_importing_never_runs_the_folders_reward_code(drfc_copy: Path, tmp_path: Path) -> None:
    ran = tmp_path / "it-ran"
    (drfc_copy / "reward_function.py").write_text(
        f"open({str(ran)!r}, 'w').write('module-level code ran')\n"
        "def reward_function(params):\n"
        "    raise RuntimeError('only when training')\n"
    )
    result = import_deepracer_folder(drfc_copy, name="untrusted")
    assert not ran.exists()  # checked by reading it, not by running it
    assert "only when training" in result.folder.reward_source()


def test_a_folder_whose_reward_file_is_not_a_reward_function_is_refused(
    drfc_copy: Path,
) -> None:
    (drfc_copy / "reward_function.py").write_text("def reward(params):\n    return 1.0\n")
    with pytest.raises(RewardFunctionError, match="no reward_function found"):
        import_deepracer_folder(drfc_copy, name="no-function")


def test_a_known_world_name_picks_the_track(drfc_copy: Path) -> None:
    (drfc_copy / "ip" / "training_params.yaml").write_text(
        "WORLD_NAME: bowtie-chicane\nMAX_MINUTES: 30\n"
    )
    result = import_deepracer_folder(drfc_copy, name="bowtie")
    assert result.folder.training_params().world_name == "bowtie-chicane"
    assert result.folder.training_params().max_minutes == 30


def test_out_of_range_hyperparameters_are_reported_not_clamped(drfc_copy: Path) -> None:
    path = drfc_copy / "ip" / "hyperparameters.json"
    values = json.loads(path.read_text())
    values["batch_size"] = 1024
    path.write_text(json.dumps(values))
    with pytest.raises(ModelError) as caught:
        import_deepracer_folder(drfc_copy, name="clamped")
    message = str(caught.value)
    assert "hyperparameters.json" in message
    assert "batch_size must be a whole number from 32 to 512, not 1024" in message
    assert message.endswith("edit the file and import again.")
    assert list(models_dir().iterdir()) == []


def test_unknown_hyperparameter_keys_are_reported(drfc_copy: Path) -> None:
    path = drfc_copy / "ip" / "hyperparameters.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), "gamma": 0.9}))
    with pytest.raises(ModelError, match="unknown hyperparameter 'gamma'"):
        import_deepracer_folder(drfc_copy, name="gamma")


def test_a_folder_without_metadata_is_not_a_model(deepracer_dir: Path) -> None:
    with pytest.raises(ModelError, match=r"has no model_metadata\.json"):
        import_model(deepracer_dir / "console-logs")
    with pytest.raises(ModelError, match="does not exist"):
        import_model(deepracer_dir / "no-such-folder")


def test_a_folder_name_that_is_not_a_model_name_asks_for_one(drfc_copy: Path) -> None:
    odd = drfc_copy.rename(drfc_copy.with_name("my model"))
    with pytest.raises(ModelError, match="give one with --name"):
        import_deepracer_folder(odd)
    assert import_deepracer_folder(odd, name="mine").folder.name == "mine"


def test_a_copied_racer_tui_folder_keeps_its_policy(
    trained_model: ModelFolder, tmp_path: Path
) -> None:
    copy = shutil.copytree(trained_model.path, tmp_path / "usb-stick" / "veteran")
    result = import_model(copy, name="moved")
    assert result.folder.content_hash() == trained_model.content_hash()
    assert result.folder.status() is ModelStatus.EVALUATED
    assert not any("starts untrained" in note for note in result.notes)
    (copy / "policy.safetensors").write_bytes(pickle.dumps({"weights": [1.0]}))
    with pytest.raises(BundleError, match="not a safetensors file of tensors"):
        import_model(copy, name="tampered")
    assert not (models_dir() / "tampered").exists()


def test_the_drfc_training_history_comes_along(deepracer_dir: Path) -> None:
    folder = import_model(deepracer_dir / "drfc-model").folder
    summary = training_summary(folder)
    assert summary["episodes"] == 541  # what the Garage shows as its training
    assert summary["laps_completed"] > 0
    source = deepracer_dir / "drfc-model" / "metrics" / "TrainingMetrics.json"
    ours = TrainingMetrics(None, fname=str(folder.training_metrics_file)).metrics
    theirs = TrainingMetrics(None, fname=str(source)).metrics
    assert ours.equals(theirs)  # deepracer-utils sees the same iterations in our copy


def test_a_console_download_keeps_its_logs_and_sim_trace(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    # The console's log download beside the model's metadata (its model download).
    download = tmp_path / "console"
    shutil.copytree(deepracer_dir / "console-logs", download)
    (download / "model").mkdir()
    shutil.copyfile(
        deepracer_dir / "drfc-model" / "model" / "model_metadata.json",
        download / "model" / "model_metadata.json",
    )
    folder = import_model(download, name="from-console").folder
    assert training_summary(folder)["episodes"] == 568
    stamp = "20220612082523"
    assert [path.name for path in folder.evaluation_files()] == [f"EvaluationMetrics-{stamp}.json"]
    assert folder.best_evaluation_lap() == 16.267
    trace = download / "sim-trace" / "evaluation" / "0-iteration.csv"
    assert folder.evaluation_trace_file(stamp).read_bytes() == trace.read_bytes()
    log = DeepRacerLog(str(folder.path))
    log.load_evaluation_trace()
    laps = AnalysisUtils.simulation_agg(log.dataframe(), "stream", "episode", is_eval=True)
    trials = read_evaluation_metrics(folder.evaluation_files()[0])
    for time, trial in zip(laps["time"], trials, strict=True):
        assert trial.lap_time_seconds is not None
        assert time == pytest.approx(trial.lap_time_seconds, rel=0.01)  # DeepRacer's own data


def test_a_sim_trace_that_is_not_one_stops_the_import_by_name(drfc_copy: Path) -> None:
    (drfc_copy / "training-simtrace").mkdir()
    bad = drfc_copy / "training-simtrace" / "0-iteration.csv"
    bad.write_text("this,is,not,a,trace\n1,2,3,4,5\n")
    with pytest.raises(ModelError) as caught:
        import_deepracer_folder(drfc_copy, name="broken-trace")
    assert str(bad) in str(caught.value) and "not a DeepRacer sim-trace CSV" in str(caught.value)
    assert "\n" not in str(caught.value)
    assert list(models_dir().iterdir()) == []


def test_a_drfc_training_trace_comes_along_for_deepracer_utils(drfc_copy: Path) -> None:
    header = (
        "episode,steps,X,Y,yaw,steer,throttle,action,reward,done,all_wheels_on_track,progress,"
        "closest_waypoint,track_len,tstamp,episode_status,pause_duration\n"
    )
    (drfc_copy / "training-simtrace").mkdir()
    for iteration in (0, 1):
        rows = "".join(
            f"{iteration * 2 + episode},{step}.0,1.0,2.0,0.0,0.0,1.0,6,1.0,{step == 3},True,"
            f"{step * 3.0},1,17.7,{100 * iteration + 10 * episode + step / 15:.3f},"
            f"{'prepare' if step == 1 else 'in_progress'},0.0\n"
            for episode in (0, 1)
            for step in (1, 2, 3)
        )
        (drfc_copy / "training-simtrace" / f"{iteration}-iteration.csv").write_text(header + rows)
    folder = import_deepracer_folder(drfc_copy, name="with-trace").folder
    log = DeepRacerLog(str(folder.path))
    log.load()
    assert sorted(set(log.dataframe()["unique_episode"])) == [0, 1, 2, 3]


def test_a_note_with_a_remedy_is_still_the_sentence_the_cli_prints(deepracer_dir: Path) -> None:
    """Front ends may word a note's remedy their own way (`Note.problem`, `Note.fix`); as a
    string it is the command line's sentence, and it serialises as one."""
    result = import_model(deepracer_dir / "drfc-model")
    untrained = next(n for n in result.notes if "starts untrained" in n)
    assert isinstance(untrained, Note) and untrained.fix is Fix.TRAIN_MODEL
    assert str(untrained) == f"{untrained.problem}: train it with `racer-tui train drfc-model`."
    assert json.loads(json.dumps(list(result.notes))) == [str(n) for n in result.notes]

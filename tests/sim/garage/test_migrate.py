"""Model folders of racer-tui's old flat layout become DRfC model folders on first open.

The old folder is written by hand here, file by file as racer-tui used to write it, so the
test does not depend on code that no longer writes that layout.
"""

from __future__ import annotations

import itertools
import json
import os
import shutil
from pathlib import Path

import pytest
from deepracer.logs import DeepRacerLog

from racer_tui.cli.main import main
from sim.deepracer.files import read_training_metrics
from sim.garage import migrate
from sim.garage.folder import ModelError, ModelStatus, list_models, models_dir, open_model
from sim.garage.options import new_model
from tests.sim.garage.helpers import policy_bytes

OLD_HEADER = (
    "episode,steps,X,Y,yaw,steer,throttle,action,reward,done,all_wheels_on_track,progress,"
    "closest_waypoint,track_len,tstamp,episode_status,pause_duration\n"
)


def _evaluation(lap_ms: int) -> str:
    trial = {
        "completion_percentage": 100,
        "metric_time": lap_ms,
        "start_time": 0,
        "elapsed_time_in_milliseconds": lap_ms,
        "episode_status": "Lap complete",
        "crash_count": 0,
        "immobilized_count": 0,
        "off_track_count": 0,
        "reversed_count": 0,
        "reset_count": 0,
        "trial": 1,
    }
    return json.dumps({"metrics": [trial]}) + "\n"


def _old_trace(steps: int) -> str:
    rows = [
        f"0,{k}.0,{k * 0.1},0.5,0.0,0.0,2.0,3,1.0,{k == steps},True,{k * 5.0},{k},17.7,"
        f"{k / 15:.3f},{'prepare' if k == 1 else 'in_progress'},0.0\n"
        for k in range(1, steps + 1)
    ]
    return OLD_HEADER + "".join(rows)


def _old_training_metrics(episodes: int) -> str:
    rows = [
        {
            "reward_score": 10 + n,
            "metric_time": 1000 * n,
            "start_time": 1000 * n - 500,
            "elapsed_time_in_milliseconds": 500,
            "episode": n,
            "trial": n,  # the old layout numbered trials like episodes
            "phase": "training",
            "completion_percentage": 12.5,
            "episode_status": "Off track",
        }
        for n in range(1, episodes + 1)
    ]
    return json.dumps({"metrics": rows, "version": 2.0, "best_model_metric": "progress"}) + "\n"


@pytest.fixture
def old_folder() -> Path:
    """A trained and twice-evaluated model in the old flat layout (two evaluations within
    one second, as the old code named them)."""
    template = new_model("template")  # the DeepRacer files' content, written fresh
    folder = models_dir() / "oldie"
    folder.mkdir()
    files = {
        "model_metadata.json": template.metadata_file.read_text(),
        "hyperparameters.json": json.dumps(
            {**template.hyperparameters(), "num_episodes_between_training": 5}
        ),
        "training_params.yaml": template.training_params_file.read_text(),
        "reward_function.py": template.reward_source(),
        "training.json": _old_training_metrics(12),
        "evaluation-20250101120000.json": _evaluation(9500),
        "evaluation-2025010112000001.json": _evaluation(9100),
        "sim-trace/evaluation/20250101120000-iteration.csv": _old_trace(4),
        "sim-trace/evaluation/2025010112000001-iteration.csv": _old_trace(5),
        "sim-trace/training/1-iteration.csv": _old_trace(3),
        "sim-trace/training/2-iteration.csv": _old_trace(6),
        "training-state.json": json.dumps({"state": "finished", "pid": 1, "steps": 99}),
        "reward_function.bundle.txt": "# kept for reading\n",
        "notes.txt": "my own notes\n",
    }
    shutil.rmtree(template.path)
    for name, text in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    (folder / "policy.safetensors").write_bytes(policy_bytes())
    (folder / "checkpoints").mkdir()
    (folder / "checkpoints" / "latest.safetensors").write_bytes(policy_bytes(1))
    return folder


def _contents(folder: Path) -> dict[str, bytes]:
    return {
        path.relative_to(folder).as_posix(): path.read_bytes()
        for path in folder.rglob("*")
        if path.is_file()
    }


def test_an_old_folder_moves_into_the_drfc_layout_and_nothing_is_lost(old_folder: Path) -> None:
    before = _contents(old_folder)
    folder = open_model("oldie")
    after = _contents(old_folder)

    moved = {
        "model_metadata.json": "model/model_metadata.json",
        "hyperparameters.json": "ip/hyperparameters.json",
        "evaluation-20250101120000.json": "metrics/EvaluationMetrics-20250101120000.json",
        # The second evaluation of that second takes the next one: DRfC names hold 14 digits.
        "evaluation-2025010112000001.json": "metrics/EvaluationMetrics-20250101120001.json",
        "sim-trace/evaluation/20250101120000-iteration.csv": (
            "evaluation-20250101120000/evaluation-simtrace/0-iteration.csv"
        ),
        "sim-trace/evaluation/2025010112000001-iteration.csv": (
            "evaluation-20250101120001/evaluation-simtrace/0-iteration.csv"
        ),
        # The old training traces (one car, a clock that stood still) are kept aside.
        "sim-trace/training/1-iteration.csv": "old-layout/sim-trace/training/1-iteration.csv",
        "sim-trace/training/2-iteration.csv": "old-layout/sim-trace/training/2-iteration.csv",
    }
    for old, new in moved.items():
        assert after[new] == before[old], old
    kept = [
        "training_params.yaml",
        "reward_function.py",
        "training-state.json",
        "reward_function.bundle.txt",
        "notes.txt",
        "policy.safetensors",
        "checkpoints/latest.safetensors",
    ]
    for name in kept:
        assert after[name] == before[name], name
    # Every row of the training metrics is there, with trials counted per iteration of 5.
    metrics = read_training_metrics(folder.training_metrics_file)
    assert [row.episode for row in metrics.episodes] == list(range(1, 13))
    assert [row.trial for row in metrics.episodes] == [1, 2, 3, 4, 5] * 2 + [1, 2]
    assert [row.reward_score for row in metrics.episodes] == [10 + n for n in range(1, 13)]
    assert set(after) == set(kept) | set(moved.values()) | {"metrics/TrainingMetrics.json"}
    assert not (old_folder / "sim-trace").exists()

    # The racer sees the same model, and deepracer-utils sees a DRfC folder.
    assert folder.status() is ModelStatus.EVALUATED
    assert folder.best_evaluation_lap() == 9.1
    assert folder.metadata().sensors == ("vector",)
    log = DeepRacerLog(str(folder.path))
    log.load_evaluation_trace()
    assert sorted(set(log.dataframe()["stream"])) == ["20250101120000", "20250101120001"]
    assert open_model("oldie") == folder  # a second open has nothing left to do


class Killed(BaseException):
    """Stands in for SIGKILL: nothing in the migration may catch it."""


def test_a_migration_killed_part_way_opens_and_finishes_next_time(
    old_folder: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    reference = tmp_path / "reference"
    shutil.copytree(old_folder, reference)
    migrate.migrate_folder(reference)
    expected = _contents(reference)
    pristine = tmp_path / "pristine"
    shutil.copytree(old_folder, pristine)

    real_replace = os.replace
    for allowed in itertools.count():
        shutil.rmtree(old_folder)
        shutil.copytree(pristine, old_folder)
        calls = 0

        def dying_replace(source: object, target: object, _allowed: int = allowed) -> None:
            # Every rename counts, the plan's and the atomic writes' alike.
            nonlocal calls
            if calls == _allowed:
                raise Killed
            calls += 1
            real_replace(source, target)  # type: ignore[arg-type]

        monkeypatch.setattr(os, "replace", dying_replace)
        try:
            open_model("oldie")
        except Killed:
            pass
        else:
            break  # it finished before the kill point: every point has been tried
        finally:
            monkeypatch.setattr(os, "replace", real_replace)
        # Cut short, the folder still lists and opens, and that finishes the migration.
        assert [model.name for model in list_models()] == ["oldie"], allowed
        folder = open_model("oldie")
        assert _contents(old_folder) == expected, allowed
        assert folder.best_evaluation_lap() == 9.1
    assert allowed > 10  # the plan's renames and the journal's writes were all tried


def test_a_folder_of_unknown_layout_is_one_sentence_and_left_alone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    stranger = tmp_path / "stranger"
    stranger.mkdir()
    (stranger / "weights.h5").write_bytes(b"\x89HDF")
    with pytest.raises(ModelError) as caught:
        open_model(str(stranger))
    message = str(caught.value)
    assert "model/model_metadata.json does not exist" in message
    assert "racer-tui model import PATH" in message
    assert main(["model", "show", str(stranger)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "model_metadata.json" in err
    assert [p.name for p in stranger.iterdir()] == ["weights.h5"]


def test_a_folder_without_metadata_is_not_moved_and_says_what_is_missing(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    half = models_dir() / "half"
    (half / "sim-trace" / "training").mkdir(parents=True)
    (half / "hyperparameters.json").write_text(json.dumps({"lr": 0.0001}))
    (half / "sim-trace" / "training" / "3-iteration.csv").write_text(_old_trace(2))
    before = _contents(half)
    with pytest.raises(ModelError, match=r"half/model/model_metadata\.json does not exist, so"):
        open_model("half")
    assert _contents(half) == before
    assert list_models() == []  # not a model: nothing to list
    # The AWS console's log download has a sim-trace/ too: opening it moves nothing.
    download = shutil.copytree(deepracer_dir / "console-logs", tmp_path / "console")
    before = _contents(download)
    with pytest.raises(ModelError, match="racer-tui model import PATH"):
        open_model(str(download))
    assert _contents(download) == before

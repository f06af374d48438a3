"""The submission assembler: our own model folders, real DeepRacer downloads, and one clear
message (naming the file) for anything missing or malformed."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from league.assembler import CONSOLE, DRFC, RACER_TUI, assemble
from league.errors import LeagueError
from league.store import League
from league.submissions import submit
from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import ModelMetadata, write_evaluation_metrics, write_training_metrics
from sim.foundation.remedies import Fix
from sim.garage.folder import ModelFolder, create_model
from sim.tracks.catalog import resolve_track
from tests.league.helpers import REWARD, TRACK, model_folder, training_metrics, trials


def test_a_garage_model_by_name(tmp_path: Path) -> None:
    def add_metrics(folder: ModelFolder) -> None:
        write_training_metrics(folder.training_metrics_file, training_metrics(30))
        write_evaluation_metrics(
            folder.evaluation_metrics_file("20240501120000"), trials([11.5, 11.25])
        )

    model = create_model(
        "fast-one",
        track=TRACK,
        metadata=ModelMetadata(discrete_grid(), ("lidar",)),
        hyperparameters={"lr": 0.0001},
        reward_source=REWARD,
        populate=add_metrics,
    )
    submission = assemble("fast-one", "ana")
    assert submission.source == RACER_TUI
    assert submission.model_name == "fast-one"
    assert submission.model_hash == model.content_hash()
    assert submission.track_hash == resolve_track(TRACK).content_hash
    assert submission.best_lap == 11.25
    assert submission.sensors == ["lidar"]
    assert submission.hyperparameters is not None
    assert submission.hyperparameters["lr"] == 0.0001
    assert submission.training is not None
    assert submission.training["episodes"] == 30
    assert submission.action_space == {
        "type": "discrete",
        "actions": len(discrete_grid().actions),
        "speed": [min(a.speed for a in discrete_grid().actions), discrete_grid().max_speed],
        "steering": [-30.0, 30.0],
    }


def test_a_model_folder_by_path_uses_the_latest_evaluation_unless_one_is_named(
    tmp_path: Path,
) -> None:
    folder = model_folder(tmp_path, laps=(13.0, 12.0))
    later = folder / "metrics" / "EvaluationMetrics-20240601120000.json"
    write_evaluation_metrics(later, trials([10.5]))
    assert assemble(str(folder), "ana").best_lap == 10.5
    earlier = Path("metrics/EvaluationMetrics-20240501120000.json")
    named = assemble(str(folder), "ana", evaluation=earlier)
    assert named.best_lap == 12.0
    assert named.evaluation_file == "EvaluationMetrics-20240501120000.json"


def test_the_drfc_model_folder_submits_with_a_track(deepracer_dir: Path, league: League) -> None:
    submission = assemble(str(deepracer_dir / "drfc-model"), "ana", track="reinvent_base")
    assert submission.source == DRFC
    assert submission.evaluation_file == "EvaluationMetrics-20220709200711.json"
    # Three continuous laps, statuses "In progress"/"Lap complete" at 100 %: all count.
    assert len(submission.completed_laps) == 3
    assert submission.action_space is not None
    assert submission.action_space["actions"] == 14
    assert submission.sensors == ["camera"]
    assert submission.training is not None
    assert submission.training["episodes"] > 0
    stored = submit(league, submission)
    assert not stored.duplicate
    laps = league.query(
        "SELECT time_seconds FROM submission_laps WHERE submission_id = ? ORDER BY number",
        (stored.submission_id,),
    )
    assert len(laps) == 3 and min(lap[0] for lap in laps) == submission.best_lap


def test_the_console_log_download_submits_with_a_track(deepracer_dir: Path) -> None:
    submission = assemble(str(deepracer_dir / "console-logs"), "ana", track="re:Invent 2018")
    assert submission.track_name == "reinvent_base"
    assert submission.source == CONSOLE
    assert submission.best_lap == pytest.approx(16.267)
    assert [lap.time_seconds for lap in submission.laps] == pytest.approx([16.468, 16.267, 16.402])
    assert submission.action_space is None  # the console download has no model metadata


def test_a_download_without_a_track_asks_for_one(deepracer_dir: Path) -> None:
    with pytest.raises(LeagueError, match="--track"):
        assemble(str(deepracer_dir / "console-logs"), "ana")


def test_an_unknown_world_name_asks_for_a_track(tmp_path: Path) -> None:
    folder = model_folder(tmp_path)
    params = folder / "training_params.yaml"
    params.write_text(params.read_text().replace("beginner-oval", "no_such_world"))
    with pytest.raises(LeagueError, match=r"no_such_world.*--track"):
        assemble(str(folder), "ana")
    assert assemble(str(folder), "ana", track=TRACK).track_name == TRACK


@pytest.mark.parametrize(
    ("file_name", "content", "problem"),
    [
        ("metrics/EvaluationMetrics-20240501120000.json", "{not json", "not valid JSON"),
        ("metrics/EvaluationMetrics-20240501120000.json", '{"metrics": [{"trial": 1}]}', "has no"),
        ("model/model_metadata.json", '{"sensor": ["CAMERA"]}', "action_space"),
        ("ip/hyperparameters.json", '{"lr": 5}', "lr must be"),
        ("metrics/TrainingMetrics.json", '{"metrics": 3}', "metrics"),
        ("training_params.yaml", "WORLD_NAME: [", "not valid YAML"),
    ],
)
def test_a_malformed_file_is_named_and_nothing_is_written(
    tmp_path: Path, league: League, file_name: str, content: str, problem: str
) -> None:
    folder = model_folder(tmp_path)
    (folder / file_name).write_text(content)
    with pytest.raises(LeagueError) as error:
        submit(league, assemble(str(folder), "ana"))
    message = str(error.value)
    assert file_name in message and problem in message
    assert "\n" not in message
    assert league.query("SELECT count(*) FROM submissions")[0][0] == 0
    assert league.query("SELECT count(*) FROM racers")[0][0] == 0


@pytest.mark.parametrize("missing", ["ip/hyperparameters.json", "training_params.yaml"])
def test_a_missing_file_of_our_own_folder_is_named(tmp_path: Path, missing: str) -> None:
    folder = model_folder(tmp_path)
    (folder / missing).unlink()
    with pytest.raises(LeagueError, match=rf"{missing}: the file does not exist"):
        assemble(str(folder), "ana", track=TRACK)


def test_no_evaluation_says_to_evaluate_first(tmp_path: Path) -> None:
    folder = model_folder(tmp_path)
    for path in folder.glob("metrics/EvaluationMetrics-*.json"):
        path.unlink()
    with pytest.raises(LeagueError, match="no evaluation metrics") as raised:
        assemble(str(folder), "ana")
    # The command line's remedy names --evaluation; the app says its own (sim.foundation.remedies).
    assert raised.value.fix is Fix.EVALUATE_MODEL and "--evaluation" not in raised.value.problem


def test_a_drfc_folder_without_metadata_is_named(deepracer_dir: Path, tmp_path: Path) -> None:
    copy = tmp_path / "drfc"
    shutil.copytree(deepracer_dir / "drfc-model", copy)
    (copy / "model" / "model_metadata.json").unlink()
    with pytest.raises(LeagueError, match=r"model_metadata\.json: the file does not exist"):
        assemble(str(copy), "ana", track=TRACK)


def test_an_unknown_model_or_a_bad_racer_name_is_refused(tmp_path: Path) -> None:
    with pytest.raises(LeagueError, match="no model named 'ghost'"):
        assemble("ghost", "ana")
    folder = model_folder(tmp_path)
    with pytest.raises(LeagueError, match="racer name"):
        assemble(str(folder), "line\nbreak")


def test_the_evaluation_file_must_have_trials(tmp_path: Path) -> None:
    folder = model_folder(tmp_path)
    evaluation = folder / "metrics" / "EvaluationMetrics-20240501120000.json"
    evaluation.write_text(json.dumps({"metrics": []}))
    with pytest.raises(LeagueError, match="no trials"):
        assemble(str(folder), "ana")

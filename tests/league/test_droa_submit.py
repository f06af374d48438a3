"""`racer-tui submit` on DeepRacer on AWS's files: a downloaded model's folder, an imported
model, and a folder of leaderboard submissions alone."""

from __future__ import annotations

import shutil
import tarfile
from pathlib import Path

import pytest
import yaml

from league.store import League
from league.submissions import submit_model
from sim.garage.importing import import_model
from sim.physics.labels import DEEPRACER
from tests.sim.garage.droa_archives import virtual_model_archive


def _extracted(archive: Path, into: Path) -> Path:
    into.mkdir()
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    return into


def test_a_downloaded_virtual_model_submits_its_latest_run_on_its_track(
    league: League, deepracer_dir: Path, tmp_path: Path
) -> None:
    folder = _extracted(virtual_model_archive(deepracer_dir, tmp_path), tmp_path / "droa")
    submission, _ = submit_model(league, str(folder), "ana")
    # WORLD_NAME 2022_april_open, TRACK_DIRECTION_CLOCKWISE true: the clockwise track.
    assert submission.track_name == "2022_april_open_cw"
    assert submission.physics == DEEPRACER
    # The newest run is the leaderboard submission of 2026-07-25.
    assert "2026-07-25T09:00:41.918Z" in submission.evaluation_file
    assert len(submission.laps) == 3


def test_an_imported_droa_model_submits(
    league: League, deepracer_dir: Path, tmp_path: Path
) -> None:
    imported = import_model(virtual_model_archive(deepracer_dir, tmp_path)).folder
    submission, _ = submit_model(league, imported.name, "bob")
    assert submission.track_name == "2022_april_open_cw"
    assert submission.completed_laps


def test_a_folder_of_submissions_alone_submits(
    league: League, deepracer_dir: Path, tmp_path: Path
) -> None:
    full = _extracted(virtual_model_archive(deepracer_dir, tmp_path), tmp_path / "full")
    only = tmp_path / "only-submissions"
    shutil.copytree(full / "metrics" / "submission", only / "metrics" / "submission")
    shutil.copy(full / "training_params.yaml", only / "training_params.yaml")
    submission, _ = submit_model(league, str(only), "cy")
    assert submission.track_name == "2022_april_open_cw"
    assert len(submission.laps) == 3


def test_a_direction_droa_refuses_is_said_on_submit(
    league: League, deepracer_dir: Path, tmp_path: Path
) -> None:
    from league.errors import LeagueError

    folder = _extracted(virtual_model_archive(deepracer_dir, tmp_path), tmp_path / "droa")
    params = yaml.safe_load((folder / "training_params.yaml").read_text())
    params.update(WORLD_NAME="Albert", TRACK_DIRECTION_CLOCKWISE=False)
    (folder / "training_params.yaml").write_text(yaml.safe_dump(params))
    with pytest.raises(LeagueError, match="not available in direction COUNTER_CLOCKWISE"):
        submit_model(league, str(folder), "dee")

"""A DeepRacer model folder with DeepRacer's own frozen weights drives in racer-tui: the best
checkpoint's model_<N>.pb, as deepracer_checkpoints.json names it, packed with the metadata
as the car's archive; `--untrained` (or weights that cannot drive) starts it afresh."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from sim.car_archive.archive import read_car_archive
from sim.car_archive.graph_def import read_graph
from sim.car_archive.graph_runner import GraphRunner
from sim.garage.frozen_graph import frozen_graph
from sim.garage.importing import import_model
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import run_trials
from sim.training.policy_driver import driver_for_model
from tests.sim.car_export.graphs import METADATA, camera_policy_graph


def drfc_folder(root: Path, best: int | None = 2, graphs: dict[int, bytes] | None = None) -> Path:
    """DeepRacer for Cloud's layout: model/ with the metadata, frozen checkpoints and the
    checkpoints file naming the best."""
    model = root / "model"
    model.mkdir(parents=True)
    (model / "model_metadata.json").write_text(json.dumps(METADATA))
    for number, graph in (
        graphs or {2: camera_policy_graph(seed=2), 5: camera_policy_graph(seed=5)}
    ).items():
        (model / f"model_{number}.pb").write_bytes(graph)
    if best is not None:
        checkpoints = {
            "best_checkpoint": {"name": f"{best}_Step-1234.ckpt", "avg_eval_metric": 90.0},
            "last_checkpoint": {"name": "5_Step-3000.ckpt", "avg_eval_metric": 40.0},
        }
        (model / "deepracer_checkpoints.json").write_text(json.dumps(checkpoints))
    return root


def test_the_best_checkpoint_is_the_graph_deepracer_would_drive_with(tmp_path: Path) -> None:
    assert frozen_graph(drfc_folder(tmp_path / "a")) == tmp_path / "a/model/model_2.pb"
    # Without the checkpoints file: the newest frozen checkpoint.
    assert frozen_graph(drfc_folder(tmp_path / "b", best=None)) == tmp_path / "b/model/model_5.pb"
    # SageMaker's output folder keeps the best one as agent/model.pb.
    sagemaker = tmp_path / "c"
    (sagemaker / "agent").mkdir(parents=True)
    (sagemaker / "agent" / "model.pb").write_bytes(camera_policy_graph())
    assert frozen_graph(sagemaker) == sagemaker / "agent" / "model.pb"
    (tmp_path / "d").mkdir()
    assert frozen_graph(tmp_path / "d") is None


def test_an_imported_folder_drives_with_deepracer_s_own_weights(tmp_path: Path) -> None:
    result = import_model(drfc_folder(tmp_path / "drfc-car"))
    folder = result.folder
    assert folder.has_car_archive() and not folder.policy_file.exists()
    assert any("model/model_2.pb" in str(note) for note in result.notes)
    archive = read_car_archive(folder.car_archive_file)
    frames = np.random.default_rng(0).integers(0, 256, (4, 120, 160, 1)).astype(np.float32)

    best = GraphRunner(read_graph(camera_policy_graph(seed=2), "best"), archive.output_node)
    ours = GraphRunner(archive.graph, archive.output_node)
    np.testing.assert_array_equal(
        ours.run({archive.input_node: frames}), best.run({archive.input_node: frames})
    )
    trials = run_trials(driver_for_model(folder), resolve_track("reinvent_base"), 2, seed=0)
    assert all(trial.progress > 0 for trial in trials)


def test_untrained_leaves_the_weights_behind(tmp_path: Path) -> None:
    result = import_model(drfc_folder(tmp_path / "fresh"), untrained=True)
    assert not result.folder.has_policy()
    assert any("starts untrained" in str(note) for note in result.notes)


def test_weights_that_cannot_drive_start_it_untrained_and_say_why(tmp_path: Path) -> None:
    result = import_model(drfc_folder(tmp_path / "broken", graphs={2: b"\x0a\x05junk"}))
    assert not result.folder.has_policy()
    notes = " ".join(str(note) for note in result.notes)
    assert "cannot drive in racer-tui" in notes and "model_2.pb" in notes
    assert "starts untrained" in notes

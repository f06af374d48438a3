"""A physical DeepRacer from the command line: `model export --format car`, `model import`
of a car archive, `model act` on a picture, and the round trip that proves the car gets the
policy racer-tui trained: exported, imported and raced with the same seed, it drives the
same laps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sim.car_export.frame import car_frame
from sim.garage.folder import ModelFolder, open_model
from sim.garage.options import new_model
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import run_trials
from sim.training.policy_driver import driver_for_model
from tests.conftest import SHARED_DEEPRACER
from tests.racer_tui.test_league_cli import run_cli, wide_terminal  # noqa: F401 (autouse)
from tests.sim.car_export.graphs import one_sentence
from tests.sim.car_export.test_export import train_briefly

SAMPLE = SHARED_DEEPRACER / "car-model" / "sample-model.tar.gz"
DEMO = SHARED_DEEPRACER / "car-model" / "dr-demo-1.png"
# What TensorFlow gives for dr-demo-1.png (the shared README: bicubic to 160x120, then
# 0.2989 R + 0.5870 G + 0.1140 B, fed raw).
TENSORFLOW = [0.0059, 0.0070, 0.0519, 0.0149, 0.0715, 0.0073, 0.3912, 0.0326, 0.1142]
TENSORFLOW += [0.0164, 0.2474, 0.0397]
needs_sample = pytest.mark.skipif(not SAMPLE.is_file(), reason="../shared/deepracer is absent")


@pytest.fixture
def trained() -> ModelFolder:
    return train_briefly(new_model("cam", sensors=["camera"]))


def test_a_trained_model_exports_for_the_car_and_says_how_the_car_drives_it(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    out_file = tmp_path / "for-my-car"
    code, out, err = run_cli(
        capsys, "model", "export", "cam", "--format", "car", "-o", str(out_file)
    )
    assert (code, err) == (0, "")
    assert (tmp_path / "for-my-car.tar.gz").is_file()
    assert "On a DeepRacer car" in out and "100% left" in out and "80%" in out
    code, out, _ = run_cli(
        capsys, "model", "export", "cam", "--format", "car", "-o", str(out_file), "--json"
    )
    assert code == 2  # the file exists and --force was not given
    code, out, _ = run_cli(
        capsys,
        "model",
        "export",
        "cam",
        "--format",
        "car",
        "-o",
        str(out_file),
        "--force",
        "--json",
    )
    data = json.loads(out)
    assert data["path"] == str(tmp_path / "for-my-car.tar.gz")
    speeds = {row["speed"] for row in data["on_the_car"]}
    top = max(speeds)
    for row in data["on_the_car"]:
        if row["speed"] == top / 2:
            assert row["throttle"] == pytest.approx(0.8)
    assert max(row["throttle"] for row in data["on_the_car"]) == pytest.approx(1.0)


def test_the_round_trip_drives_the_same_laps(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    archive = tmp_path / "cam.tar.gz"
    assert run_cli(capsys, "model", "export", "cam", "--format", "car", "-o", str(archive))[0] == 0
    code, out, err = run_cli(capsys, "model", "import", str(archive), "--name", "cam-car")
    assert (code, err) == (0, "")
    assert "Next: racer-tui evaluate cam-car" in out
    imported = open_model("cam-car")
    assert imported.has_car_archive() and not imported.policy_file.exists()
    track = resolve_track("reinvent_base")
    original = run_trials(driver_for_model(trained), track, 3, seed=5)
    again = run_trials(driver_for_model(imported), track, 3, seed=5)
    assert [trial.progress for trial in again] == [trial.progress for trial in original]
    assert [trial.seconds for trial in again] == [trial.seconds for trial in original]
    assert [trial.resets for trial in again] == [trial.resets for trial in original]
    # And a race: the same laps, off-tracks and every action on the way.
    rules = RaceRules(window_seconds=90.0)
    raced = run_race(track, rules, driver_for_model(trained), seed=5)
    raced_again = run_race(track, rules, driver_for_model(imported), seed=5)
    assert raced_again.laps == raced.laps
    assert raced_again.total_offtracks == raced.total_offtracks
    assert raced.trace is not None and raced_again.trace is not None
    assert len(raced.trace.t) > 1000  # 90 s of driving, every step compared
    assert np.array_equal(raced_again.trace.action, raced.trace.action)
    assert np.array_equal(raced_again.trace.x, raced.trace.x)
    assert raced_again.model_name == "cam-car" and raced.model_name == "cam"
    assert [trial.status for trial in again] == [trial.status for trial in original]


@needs_sample
def test_the_deepracer_trained_archive_imports_acts_and_races(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, err = run_cli(capsys, "model", "import", str(SAMPLE))
    assert (code, err) == (0, "")
    code, out, _ = run_cli(capsys, "model", "act", "sample-model", str(DEMO), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["action"]["index"] == 6  # 0 degrees at 2 m/s, as TensorFlow chooses
    assert data["frame_size"] == [160, 120]
    # The car's bilinear resize moves TensorFlow's bicubic numbers by a few hundredths.
    np.testing.assert_allclose(data["outputs"], TENSORFLOW, atol=0.03)
    # A picture already at the car's size and grey is fed as it is: TensorFlow's numbers.
    prepared = tmp_path / "prepared.png"
    _save_prepared_demo(prepared)
    code, out, _ = run_cli(capsys, "model", "act", str(SAMPLE), str(prepared), "--json")
    np.testing.assert_allclose(json.loads(out)["outputs"], TENSORFLOW, atol=2e-3)
    code, out, err = run_cli(
        capsys, "--race", "sample-model", "--track", "reinvent_base", "--json", "--seed", "0"
    )
    assert (code, err) == (0, "")
    race = json.loads(out)["races"][0]
    assert race["model_name"] == "sample-model"
    assert race["laps"] and race["best_lap_seconds"] > 0, "it completes laps in racer-tui"


def _save_prepared_demo(path: Path) -> None:
    """dr-demo-1.png as the README prepared it for TensorFlow, rounded to 8-bit grey."""
    from PIL import Image

    with Image.open(DEMO) as image:
        small = image.convert("RGB").resize((160, 120), Image.Resampling.BICUBIC)
    grey = np.asarray(small, dtype=np.float64) @ np.array([0.2989, 0.5870, 0.1140])
    Image.fromarray(np.clip(np.rint(grey), 0, 255).astype(np.uint8), mode="L").save(path)


def test_an_imported_archive_cannot_be_trained_cloned_or_bundled(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    archive = tmp_path / "cam.tar.gz"
    run_cli(capsys, "model", "export", "cam", "--format", "car", "-o", str(archive))
    run_cli(capsys, "model", "import", str(archive), "--name", "cam-car")
    for args in (
        ("train", "cam-car"),
        ("model", "clone", "cam-car", "again"),
        ("model", "export", "cam-car"),
    ):
        code, _out, err = run_cli(capsys, *args)
        assert code == 2, args
        message = err.strip().removeprefix("racer-tui: ")
        assert "car archive" in message and one_sentence(message), message
    # ... but it goes back to the car as it came.
    again = tmp_path / "again.tar.gz"
    code, _, _ = run_cli(capsys, "model", "export", "cam-car", "--format", "car", "-o", str(again))
    assert code == 0 and again.read_bytes() == archive.read_bytes()


def test_bad_pictures_and_archives_get_one_sentence(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    text = tmp_path / "notes.png"
    text.write_text("not a picture")
    broken = tmp_path / "broken.tar.gz"
    broken.write_bytes(b"\x1f\x8b truncated")
    for args in (
        ("model", "act", "cam", str(text)),
        ("model", "act", "cam", str(tmp_path / "missing.png")),
        ("model", "import", str(broken)),
    ):
        code, _out, err = run_cli(capsys, *args)
        assert code == 2, args
        message = err.strip().removeprefix("racer-tui: ")
        assert one_sentence(message) and "Traceback" not in err, message


def test_model_act_prepares_a_picture_as_the_car_does() -> None:
    """OpenCV's INTER_LINEAR at an exact 4x reduction averages the middle 2x2 of each 4x4
    block; BT.601 grey weights."""
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (480, 640, 3)).astype(np.uint8)
    frame = car_frame(rgb)
    assert frame.shape == (120, 160) and frame.dtype == np.uint8
    block = (
        rgb[1::4, 1::4].astype(np.float64) + rgb[1::4, 2::4] + rgb[2::4, 1::4] + rgb[2::4, 2::4]
    ) / 4
    expected = np.rint(block @ np.array([0.299, 0.587, 0.114]))
    assert np.abs(frame.astype(np.float64) - expected).max() <= 1
    flat = np.full((37, 53, 3), (200, 100, 50), dtype=np.uint8)
    assert (car_frame(flat) == round(0.299 * 200 + 0.587 * 100 + 0.114 * 50)).all()


def test_model_new_trains_for_the_real_world_on_request(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, err = run_cli(
        capsys, "model", "new", "real", "--sensor", "camera", "--camera-randomisation", "on"
    )
    assert (code, err) == (0, "")
    code, out, _ = run_cli(capsys, "model", "show", "real", "--json")
    assert "sensor noise 1" in json.loads(out)["camera_randomisation"]
    code, out, _ = run_cli(capsys, "model", "show", "real")
    assert "camera randomisation" in out and "light and contrast 1" in out
    for args, words in (
        (("model", "new", "bad", "--sensor", "camera", "--camera-randomisation", "fog"), "'fog'"),
        (("model", "new", "blind", "--camera-randomisation", "on"), "needs a camera"),
    ):
        code, _, err = run_cli(capsys, *args)
        message = err.strip().removeprefix("racer-tui: ")
        assert code == 2 and words in message and one_sentence(message), message


def test_an_archive_model_keeps_the_archive_s_car_when_edited(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    """Its graph was made for its sensor and action space: an edit that changes them would
    show one car and race another, so it is refused; its track may change."""
    from dataclasses import replace

    from racer_tui.app.model_form import save_edit
    from sim.deepracer.action_space import discrete_grid
    from sim.garage.folder import ModelError
    from sim.garage.options import spec_of

    archive = tmp_path / "cam.tar.gz"
    run_cli(capsys, "model", "export", "cam", "--format", "car", "-o", str(archive))
    run_cli(capsys, "model", "import", str(archive), "--name", "cam-car")
    folder = open_model("cam-car")
    spec = spec_of(folder)
    faster = replace(spec.metadata, action_space=discrete_grid(30.0, 5, 4.0, 2))
    with pytest.raises(ModelError) as raised:
        save_edit(folder, replace(spec, metadata=faster))
    assert one_sentence(str(raised.value)) and "car archive" in str(raised.value)
    assert folder.metadata() == spec.metadata
    save_edit(folder, replace(spec, track="reInvent2019_wide"))
    assert folder.training_params().world_name == "reInvent2019_wide"
    # It was trained in DeepRacer's simulator (its weights), which `model show` says without
    # telling the racer to train it again.
    _code, out, _ = run_cli(capsys, "model", "show", "cam-car", "--json")
    details = json.loads(out)
    assert "train it again" not in (details["physics_note"] or "")
    assert "DeepRacer's simulator" in details["physics_note"]
    assert details["car_archive"] is True
    _code, out, _ = run_cli(capsys, "model", "show", "cam-car")
    assert "a DeepRacer car archive, never trained here" in out
    assert "reward function" not in out


def test_exports_go_where_asked_or_say_why_they_cannot(
    capsys: pytest.CaptureFixture[str], trained: ModelFolder, tmp_path: Path
) -> None:
    code, _, _ = run_cli(capsys, "model", "export", "cam", "--format", "car", "-o", str(tmp_path))
    assert code == 0 and (tmp_path / "cam.tar.gz").is_file()  # a folder: NAME inside it
    blocked = tmp_path / "a-file"  # a file where a folder would have to be (even root
    blocked.write_text("not a folder")  # cannot write below it)
    for fmt in ("car", "bundle"):
        out_file = str(blocked / "x")
        code, _, err = run_cli(capsys, "model", "export", "cam", "--format", fmt, "-o", out_file)
        message = err.strip().removeprefix("racer-tui: ")
        assert code == 2 and "cannot write" in message and one_sentence(message), message
    code, _, err = run_cli(capsys, "model", "act", str(tmp_path / "gone.tar.gz"), str(DEMO))
    assert code == 2 and "does not exist" in err

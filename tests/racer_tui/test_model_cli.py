"""`racer-tui model ...`: what a racer types and sees, and one-line errors with exit code 2."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import pytest

from racer_tui.cli.main import main
from sim.garage.folder import models_dir, open_model
from sim.training.config import model_env_config
from tests.sim.garage.helpers import add_evaluation, add_policy, write_training_state
from tests.test_architecture import _import_report


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_new_list_and_show(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(
        capsys, "model", "new", "speedy", "--max-speed", "4", "--hp", "lr=0.0001"
    )
    assert code == 0
    assert "Created model speedy" in out
    assert "racer-tui train speedy" in out
    code, out, _ = run_cli(capsys, "model", "list", "--json")
    assert json.loads(out) == [
        {
            "name": "speedy",
            "status": "untrained",
            "track": "reinvent_base",
            "race": "time trial",
            "sensor": "vector",
            "actions": "10 discrete, up to 4 m/s",
            "best_lap_s": None,
            "evaluated_before_training": False,
        }
    ]
    code, out, _ = run_cli(capsys, "model", "show", "speedy", "--json")
    details = json.loads(out)
    assert details["hyperparameters"]["lr"] == 0.0001
    assert len(details["actions"]) == 10
    assert details["reward_function"] == "template follow_center_line"
    assert details["metadata"]["sensor"] == ["VECTOR"]
    assert details["training"]["episodes"] == 0


@pytest.mark.parametrize("track", ["reinvent_base", "re:Invent 2018", "Expedition Loop"])
def test_a_new_model_on_an_official_track_by_either_name(
    capsys: pytest.CaptureFixture[str], track: str
) -> None:
    code, _, err = run_cli(capsys, "model", "new", "official", "--track", track)
    assert code == 0, err
    world = "red_star_open" if track == "Expedition Loop" else "reinvent_base"
    params = open_model("official").training_params()
    assert params.world_name == world  # the simulator's WORLD_NAME, as DeepRacer writes it


def test_a_range_starting_with_a_minus_is_taken_as_written(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The README's own example: `--steering-range -30,30`, not `--steering-range=-30,30`."""
    code, _, err = run_cli(
        capsys,
        "model",
        "new",
        "cont",
        "--continuous",
        "--steering-range",
        "-30,30",
        "--speed-range",
        "0.1,4",
    )
    assert code == 0, err
    space = open_model("cont").metadata().action_space
    assert space.kind == "continuous"
    assert space.steering_range == (-30.0, 30.0)


def test_list_and_show_as_tables(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_cli(capsys, "model", "list")[1].startswith("No models yet")
    run_cli(capsys, "model", "new", "tabled", "--sensor", "LIDAR")
    folder = open_model("tabled")
    add_policy(folder)
    add_evaluation(folder, stamp="20250101121000", lap_ms=9250)  # after its training ended
    write_training_state(folder, "finished")
    out = run_cli(capsys, "model", "list")[1]
    assert "tabled" in out and "evaluated" in out and "9.250 s" in out and "lidar" in out
    code, out, _ = run_cli(capsys, "model", "show", "tabled")
    assert code == 0
    for text in ("Action space", "Hyperparameters", "batch_size", "Training", "Lap complete"):
        assert text in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--steering-levels", "4"], "--steering-levels must be 3, 5 or 7, not 4."),
        (["--hp", "lr=0.5"], "--hp: lr must be a number from 1e-08 to 0.001, not 0.5."),
        (["--hp", "batch_size=1024"], "batch_size must be a whole number from 32 to 512"),
        (["--sensor", "sonar"], "--sensor: unknown sensor 'sonar'"),
        (["--continuous", "--speed-range", "3,1"], "--speed-range must be LOW,HIGH in m/s"),
        (["--track", "moon"], "--track: there is no track named 'moon'"),
    ],
)
def test_bad_options_are_one_line_errors(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    code, out, err = run_cli(capsys, "model", "new", "bad", *args)
    assert code == 2
    assert out == ""
    assert err.startswith("racer-tui: ") and message in err
    assert err.count("\n") == 1
    assert list(models_dir().iterdir()) == []


def test_sensor_lists_and_continuous_spaces(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(
        capsys,
        "model", "new", "wide", "--sensor", "FRONT_FACING_CAMERA,LIDAR", "--continuous",
        "--steering-range=-20,20", "--json",
    )  # fmt: skip
    assert code == 0
    row = json.loads(out)
    assert row["sensor"] == "camera+lidar"
    assert row["actions"] == "continuous -20..20 deg, 0.1..4 m/s"


def test_clone_and_refused_clone(capsys: pytest.CaptureFixture[str]) -> None:
    run_cli(capsys, "model", "new", "base")
    add_policy(open_model("base"))
    code, out, _ = run_cli(capsys, "model", "clone", "base", "base-2", "--reward", "prevent_zigzag")
    assert code == 0
    assert "continues from base's trained policy" in out
    code, _, err = run_cli(capsys, "model", "clone", "base", "base-3", "--sensor", "camera")
    assert code == 2
    assert "the sensor changes from vector to camera" in err


def test_delete_asks_or_takes_yes(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    run_cli(capsys, "model", "new", "doomed")
    monkeypatch.setattr("sys.stdin.isatty", lambda: False)
    code, _, err = run_cli(capsys, "model", "delete", "doomed")
    assert code == 2 and "add --yes" in err
    monkeypatch.setattr("sys.stdin.isatty", lambda: True)
    monkeypatch.setattr("builtins.input", lambda prompt: "n")
    assert run_cli(capsys, "model", "delete", "doomed")[0] == 1
    assert open_model("doomed")
    monkeypatch.setattr("builtins.input", lambda prompt: "y")
    assert run_cli(capsys, "model", "delete", "doomed")[0] == 0
    code, _, err = run_cli(capsys, "model", "show", "doomed")
    assert code == 2 and "no model named 'doomed'" in err


def test_delete_refuses_while_training(capsys: pytest.CaptureFixture[str]) -> None:
    run_cli(capsys, "model", "new", "busy")
    write_training_state(open_model("busy"), "running")
    code, _, err = run_cli(capsys, "model", "delete", "busy", "--yes")
    assert code == 2 and "training right now" in err


def test_import_the_real_drfc_model(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path
) -> None:
    code, out, _ = run_cli(capsys, "model", "import", str(deepracer_dir / "drfc-model"), "--json")
    assert code == 0
    report = json.loads(out)
    assert report["name"] == "drfc-model"
    assert report["sensor"] == "camera"
    assert report["best_lap_s"] == pytest.approx(13.392)
    assert any("follow_center_line template" in note for note in report["notes"])
    out = run_cli(capsys, "model", "import", str(deepracer_dir / "drfc-model"), "--name", "again")[
        1
    ]
    assert "Note: it has no reward_function.py" in out


def test_export_and_import_a_bundle(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run_cli(capsys, "model", "new", "shipped")
    code, _, err = run_cli(capsys, "model", "export", "shipped")
    assert code == 2 and "no trained policy to export" in err
    add_policy(open_model("shipped"))
    monkeypatch.chdir(tmp_path)
    code, out, _ = run_cli(capsys, "model", "export", "shipped")
    assert code == 0
    bundle = tmp_path / "shipped.racer-bundle"
    assert f"to {bundle.name}" in out and zipfile.is_zipfile(bundle)
    code, out, _ = run_cli(capsys, "model", "import", str(bundle), "--name", "received", "--json")
    assert code == 0
    assert json.loads(out)["status"] == "trained"
    assert open_model("received").content_hash() == open_model("shipped").content_hash()
    # A second export never overwrites the bundle silently.
    before = bundle.read_bytes()
    code, _, err = run_cli(capsys, "model", "export", "shipped")
    assert code == 2 and "already exists" in err and "--force" in err
    assert bundle.read_bytes() == before
    code, _, _ = run_cli(capsys, "model", "export", "shipped", "--force")
    assert code == 0 and zipfile.is_zipfile(bundle)
    bundle.write_bytes(bundle.read_bytes()[:100])
    code, _, err = run_cli(capsys, "model", "import", str(bundle), "--name", "broken")
    assert code == 2 and "not a racer-tui bundle" in err


def test_a_file_that_is_no_kind_of_model_is_named_as_such(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # Issue 42's walk: a notes file picked by mistake was called "a damaged or foreign file"
    # and told to be exported again; it is neither, and the sentence says what would do.
    notes = tmp_path / "notes.txt"
    notes.write_text("lap times from friday\n")
    code, _, err = run_cli(capsys, "model", "import", str(notes))
    assert code == 2 and "is not a model racer-tui can import" in err
    assert "damaged" not in err and "DeepRacer model folder" in err and ".tar.gz" in err
    assert not models_dir().exists() or not any(models_dir().iterdir())
    # A bundle renamed is still read as a bundle, and a broken one still says so.
    renamed = tmp_path / "from-ana.zip"
    renamed.write_bytes(b"PK\x05\x06" + bytes(18))  # an empty zip archive
    code, _, err = run_cli(capsys, "model", "import", str(renamed))
    assert code == 2 and "lacks" in err


def test_the_model_commands_stay_headless() -> None:
    report = _import_report(["racer_tui.cli.model_commands"])
    assert report["racer_tui.cli.model_commands"] == []


def test_a_model_for_object_avoidance_is_made_with_deepracers_keys(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, _ = run_cli(
        capsys, "model", "new", "dodger", "--race-type", "object-avoidance", "--obstacles", "4",
        "--randomize-obstacles", "--sensor", "lidar", "--reward", "object_avoidance",
    )  # fmt: skip
    assert code == 0
    params = open_model("dodger").training_params()
    assert params.race_type == "OBJECT_AVOIDANCE"
    assert params.extra["NUMBER_OF_OBSTACLES"] == 4
    assert params.extra["RANDOMIZE_OBSTACLE_LOCATIONS"] is True
    assert params.extra["OBSTACLE_TYPE"] == "box_obstacle"
    code, out, _ = run_cli(capsys, "model", "show", "dodger")
    assert "object avoidance, 4 boxes (random)" in out
    assert model_env_config(open_model("dodger")).race is not None  # it trains among them
    code, _, _ = run_cli(
        capsys, "model", "new", "chaser", "--sensor", "lidar", "--bots", "2", "--bot-lane-change"
    )
    assert code == 0
    params = open_model("chaser").training_params()
    assert params.race_type == "HEAD_TO_BOT" and params.extra["NUMBER_OF_BOT_CARS"] == 2
    assert params.extra["IS_LANE_CHANGE"] is True and params.extra["BOT_CAR_SPEED"] == 1.0
    code, out, _ = run_cli(capsys, "model", "show", "chaser")
    assert "head-to-bot, 2 bots at 1.0 m/s" in out and "lanes)" in out
    code, out, _ = run_cli(capsys, "model", "list")
    assert "head-to-bot" in out and "object avoidance" in out  # under each one's track
    code, _, err = run_cli(capsys, "model", "new", "x", "--bots", "2", "--obstacles", "3")
    assert code == 2 and "--obstacles and --randomize-obstacles need" in err
    code, _, err = run_cli(capsys, "model", "new", "x", "--obstacles", "11")
    assert code == 2 and "--obstacles must be from 1 to 10" in err
    # The vector state does not show objects: a model that could not see them is not made.
    code, _, err = run_cli(
        capsys, "model", "new", "blind", "--race-type", "object-avoidance", "--sensor", "vector"
    )
    assert code == 2 and "needs a camera or a lidar" in err


def test_show_names_the_network_a_vector_model_really_has(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # Issue 42, point 13: the command line said DEEP_CONVOLUTIONAL_NETWORK_SHALLOW.
    run_cli(capsys, "model", "new", "vec", "--sensor", "vector")
    code, out, _ = run_cli(capsys, "model", "show", "vec")
    assert code == 0
    assert "dense, shallow (no camera)" in out


def test_entering_a_model_still_training_says_so_as_the_app_does(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = str(tmp_path / "league.db")
    run_cli(capsys, "model", "new", "busy")
    add_policy(open_model("busy"))
    write_training_state(open_model("busy"), "running")
    run_cli(capsys, "night", "new", "--db", db, "--name", "friday")
    code, out, err = run_cli(
        capsys, "night", "add", "friday", "--racer", "ana", "--model", "busy", "--db", db
    )
    assert code == 0, err
    assert (
        "Note: busy is still training: its heat races the policy it has when the heat runs." in out
    )
    code, out, _ = run_cli(
        capsys, "night", "add", "friday", "--racer", "bo", "--model", "physical:car1", "--db", db
    )
    assert "Note: A physical car is timed by hand" in out


def test_a_physical_rules_night_notes_a_simulated_car_and_names_a_physical_car_as_one(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The host walk: a simulated car entered under the physical rules got no word, and
    `night show` called a physical car by its bare name, as if it were a garage model."""
    db = str(tmp_path / "league.db")
    run_cli(capsys, "night", "new", "--db", db, "--name", "venue", "--rules", "physical")
    code, out, err = run_cli(
        capsys, "night", "add", "venue", "--racer", "ana", "--model", "reference", "--db", db
    )
    assert code == 0, err
    assert "Note: A simulated car under the physical rules: its off-tracks add no time" in out
    code, out, _ = run_cli(
        capsys, "night", "add", "venue", "--racer", "bo", "--model", "physical:car1", "--db", db
    )
    assert "Note:" not in out  # a hand-timed car is what the physical rules are for
    run_cli(capsys, "night", "draw", "venue", "--db", db)
    code, out, _ = run_cli(capsys, "night", "show", "venue", "--db", db)
    assert code == 0
    heats_row = next(line for line in out.splitlines() if " bo " in line)
    assert "car1 (physical)" in heats_row

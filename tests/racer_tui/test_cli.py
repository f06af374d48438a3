"""The headless command line: outputs a script can rely on, one-sentence errors, exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from racer_tui.cli.main import main


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_tracks_list_json_has_the_builtin_tracks(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tracks", "list", "--json")
    assert code == 0
    names = [t["name"] for t in json.loads(out)]
    assert {"beginner-oval", "hairpin-circuit", "bowtie-chicane", "speedway", "grand-prix"} <= set(
        names
    )


def test_import_a_real_deepracer_track_then_show_it(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path
) -> None:
    source = deepracer_dir / "tracks" / "reinvent_base.npy"
    code, out, _ = run_cli(capsys, "tracks", "import", str(source), "--name", "reinvent-2018")
    assert code == 0
    assert "17.71 m" in out
    code, out, _ = run_cli(capsys, "tracks", "show", "reinvent-2018", "--json")
    facts = json.loads(out)
    assert facts["length_m"] == pytest.approx(17.71, abs=0.01)
    assert facts["reference_status"] == "Lap complete"
    assert 4.0 < facts["reference_lap_s"] < 12.0


def test_import_reverse_flips_the_direction(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path
) -> None:
    source = deepracer_dir / "tracks" / "Oval_track.npy"
    assert (
        run_cli(capsys, "tracks", "import", str(source), "--reverse", "--name", "oval-cw")[0] == 0
    )
    _, out, _ = run_cli(capsys, "tracks", "list", "--json")
    entry = next(t for t in json.loads(out) if t["name"] == "oval-cw")
    assert entry["direction"] == "clockwise"


def test_generate_is_seeded(capsys: pytest.CaptureFixture[str]) -> None:
    first = json.loads(run_cli(capsys, "tracks", "generate", "--seed", "11", "--json")[1])
    second = json.loads(run_cli(capsys, "tracks", "generate", "--seed", "11", "--json")[1])
    other = json.loads(run_cli(capsys, "tracks", "generate", "--seed", "12", "--json")[1])
    assert first == second
    assert first["length_m"] != other["length_m"]


def test_generate_save_makes_it_a_usable_track(capsys: pytest.CaptureFixture[str]) -> None:
    saved = json.loads(run_cli(capsys, "tracks", "generate", "--seed", "5", "--save", "--json")[1])
    names = [t["name"] for t in json.loads(run_cli(capsys, "tracks", "list", "--json")[1])]
    assert saved["name"] in names


@pytest.mark.parametrize(
    ("array", "problem"),
    [
        (np.zeros((10, 4)), "shape"),
        (np.full((10, 6), np.nan), "NaN"),
        (np.zeros((2, 6)), "at least 3"),
    ],
)
def test_bad_track_files_give_one_sentence_and_exit_2(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, array: np.ndarray, problem: str
) -> None:
    path = tmp_path / "broken.npy"
    np.save(path, array)
    code, out, err = run_cli(capsys, "tracks", "import", str(path))
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert "broken.npy" in err
    assert problem in err
    assert "Traceback" not in err


def test_a_track_shows_its_limit_laps_and_gives_its_racing_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`tracks show` gives the flying and standing limit laps beside the reference lap, and
    within a model's action space; `tracks line` the line with its speeds, as CSV, as a
    list a reward function pastes, or as JSON."""
    import ast

    from sim.garage.options import new_model

    new_model("slowpoke", max_speed=1.5, speed_levels=2)
    code, out, _ = run_cli(capsys, "tracks", "show", "hairpin-circuit", "--model", "slowpoke")
    assert code == 0
    code, out, _ = run_cli(
        capsys, "tracks", "show", "hairpin-circuit", "--model", "slowpoke", "--json"
    )
    facts = json.loads(out)
    flying, standing = facts["limit_flying_lap_s"], facts["limit_standing_lap_s"]
    assert flying < standing < facts["reference_lap_s"]
    assert facts["model_limit_flying_lap_s"] > flying + 1.0  # what 1.5 m/s costs
    code, out, _ = run_cli(capsys, "tracks", "line", "hairpin-circuit", "--every", "0.5")
    lines = out.splitlines()
    assert code == 0 and lines[0] == "x,y,speed" and len(lines) > 30
    code, out, _ = run_cli(capsys, "tracks", "line", "hairpin-circuit", "--python")
    source = out.split("RACING_LINE = ", 1)[1]
    points = ast.literal_eval(source)  # pastes as it prints
    # The speed to command (params["speed"]): never above the console's 4 m/s.
    assert all(len(point) == 3 and 0.1 <= point[2] <= 4.0 for point in points)
    code, out, _ = run_cli(
        capsys, "tracks", "line", "hairpin-circuit", "--python", "--model", "slowpoke"
    )
    slow = ast.literal_eval(out.split("RACING_LINE = ", 1)[1])
    assert max(point[2] for point in slow) == 1.5 and "(the action space)" in out
    code, out, _ = run_cli(capsys, "tracks", "line", "hairpin-circuit", "--json")
    line = json.loads(out)
    assert line["flying_lap_s"] == flying and line["columns"] == ["x", "y", "speed"]
    code, _, err = run_cli(capsys, "tracks", "line", "hairpin-circuit", "--every", "0")
    assert code == 2 and "--every must be a positive number" in err


def test_unknown_track_name_suggests_close_names(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_cli(capsys, "tracks", "show", "reinvent-base")
    assert code == 2
    assert "'reinvent_base'" in err
    assert "Traceback" not in err


def test_a_fresh_install_lists_the_official_tracks(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tracks", "list", "--json")

    assert code == 0
    tracks = {t["name"]: t for t in json.loads(out)}
    assert len(tracks) == 5 + 127
    reinvent = tracks["reinvent_base"]
    assert reinvent["console_name"] == "re:Invent 2018"
    assert reinvent["kind"] == "official"
    assert (reinvent["length_m"], reinvent["direction"]) == (17.71, "counter-clockwise")
    assert reinvent["release_date"] == "2020-03-01"


def test_tracks_list_filters_by_kind_and_search(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path
) -> None:
    run_cli(
        capsys,
        "tracks",
        "import",
        str(deepracer_dir / "tracks" / "Oval_track.npy"),
        "--name",
        "club",
    )

    def names(*flags: str) -> list[str]:
        return [
            t["name"] for t in json.loads(run_cli(capsys, "tracks", "list", "--json", *flags)[1])
        ]

    assert names("--imported") == ["club"]
    assert len(names("--builtin")) == 5
    assert len(names("--official")) == 127
    assert len(names("--builtin", "--imported")) == 6
    assert names("--search", "expedition") == [
        "red_star_open",
        "red_star_pro",
        "red_star_pro_ccw",
        "red_star_pro_cw",
    ]
    assert names("--search", "RE:INVENT 2018") == ["reinvent_base"]
    code, out, _ = run_cli(capsys, "tracks", "list", "--search", "no such track")
    assert code == 0 and "No track matches" in out


def test_tracks_list_table_fits_80_columns(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tracks", "list")

    assert code == 0
    assert "re:Invent 2018" in out and "Expedition Loop" in out
    assert max(len(line.rstrip()) for line in out.splitlines()) <= 80


def test_an_official_track_is_shown_by_its_console_name(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = run_cli(capsys, "tracks", "show", "Expedition Loop", "--json")

    assert code == 0
    facts = json.loads(out)
    assert facts["name"] == "red_star_open"
    assert facts["kind"] == "official"
    assert facts["reference_status"] == "Lap complete"


def test_importing_an_official_file_says_it_is_already_here(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path
) -> None:
    code, out, _ = run_cli(
        capsys, "tracks", "import", str(deepracer_dir / "tracks" / "reinvent_base.npy")
    )

    assert code == 0
    assert "already here" in " ".join(out.split())


def test_tracks_list_loads_no_simulator_and_no_array() -> None:
    script = (
        "import contextlib, io, sys\n"
        "from racer_tui.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['tracks', 'list'])\n"
        "print(sorted(m for m in ('numpy', 'scipy', 'shapely', 'sim.tracks.track', 'torch') "
        "if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_reward_check_reports_sample_and_lap_rewards(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    reward = tmp_path / "reward.py"
    reward.write_text(
        "def reward_function(params):\n"
        "    return 1.0 - params['distance_from_center'] / (params['track_width'] / 2)\n"
    )
    code, out, _ = run_cli(
        capsys, "reward", "check", str(reward), "--track", "beginner-oval", "--json"
    )
    report = json.loads(out)
    assert code == 0
    assert report["lap_steps"] > 50
    assert 0.0 < report["lap_reward_mean"] <= 1.0
    assert report["lap_reward_max"] <= 1.0


def test_reward_check_names_file_and_line_of_a_failure(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    reward = tmp_path / "broken_reward.py"
    reward.write_text("def reward_function(params):\n    x = 1\n    return params['speed'] / 0\n")
    code, _, err = run_cli(capsys, "reward", "check", str(reward))
    assert code == 2
    assert "broken_reward.py" in err
    assert "line 3" in err
    assert err.count("\n") == 1


def test_console_script_runs_without_a_terminal(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "racer_tui.cli.main", "tracks", "list", "--json"],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        check=False,
    )
    assert result.returncode == 0
    assert json.loads(result.stdout)


def test_a_timer_that_is_not_there_is_said_before_the_app_starts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "ttyUSB9"
    assert main(["--timer", str(missing)]) == 2
    said = capsys.readouterr().err
    assert said == (
        f"racer-tui: The timer {missing} cannot be found (No such file or directory); "
        "check the path.\n"
    )

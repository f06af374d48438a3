"""Race types from the command line: `--rules object-avoidance` (a preset's name) races and
records among boxes, a night opened with that preset says so, and `racer-tui leaderboard`
keeps each race type on a board of its own: a track's time trials by default,
`--race-type` for another, every board without --track, and JSON rows naming it."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from rich.console import Console

from league.nights import get_night
from league.opening import open_league
from league.races import record_race
from racer_tui.cli.main import main
from racer_tui.cli.race_commands import race_table
from sim.race.rules import preset_rules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result
from tests.racer_tui.test_league_cli import run_cli, wide_terminal  # noqa: F401 (autouse)

BOXES = preset_rules("object-avoidance")


@pytest.fixture
def db(tmp_path: Path) -> str:
    """One track, two races of each kind: ana leads the time trials, cy (quicker still)
    the object-avoidance races."""
    path = tmp_path / "league.db"
    with open_league(path) as league:
        record_race(league, race_result("ana", [10.0]))
        record_race(league, race_result("bex", [11.0]))
        record_race(league, race_result("cy", [9.0], rules=BOXES))
        record_race(league, race_result("bex", [12.5], rules=BOXES))
    return str(path)


def _rows(out: str) -> list[tuple[int, str, float, str]]:
    return [(r["rank"], r["racer"], r["best_lap"], r["race_type"]) for r in json.loads(out)]


def test_a_tracks_board_is_its_time_trials_unless_another_race_type_is_asked_for(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    board = ("leaderboard", "--db", db, "--track", TRACK, "--format", "json")

    code, out, err = run_cli(capsys, *board)
    assert code == 0, err
    assert _rows(out) == [(1, "ana", 10.0, "time_trial"), (2, "bex", 11.0, "time_trial")]

    code, out, err = run_cli(capsys, *board, "--race-type", "object-avoidance")
    assert code == 0, err
    assert _rows(out) == [
        (1, "cy", 9.0, "object_avoidance"),
        (2, "bex", 12.5, "object_avoidance"),
    ]
    assert {row["track"] for row in json.loads(out)} == {f"{TRACK} (object avoidance)"}


def test_every_board_is_printed_on_its_own_without_a_track(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    code, out, err = run_cli(capsys, "leaderboard", "--db", db)

    assert code == 0, err
    assert f"Leaderboard: {TRACK}, ranked by best lap" in out
    assert f"Leaderboard: {TRACK} (object avoidance), ranked by best lap" in out
    trials, boxes = out.split("(object avoidance)")
    assert trials.index("ana") < trials.index("bex") and "cy" not in trials
    assert boxes.index("cy") < boxes.index("bex") and "ana" not in boxes

    code, out, err = run_cli(
        capsys, "leaderboard", "--db", db, "--race-type", "object_avoidance", "--format", "json"
    )
    assert code == 0, err
    assert [row[1] for row in _rows(out)] == ["cy", "bex"]


def test_an_empty_board_says_which_race_types_the_track_has(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    board = ("leaderboard", "--db", db, "--track", TRACK, "--race-type", "head-to-bot")
    hint = (
        f"No head-to-bot laps on {TRACK} yet; its other boards: --race-type time-trial or "
        "--race-type object-avoidance."
    )

    code, out, _ = run_cli(capsys, *board)
    assert code == 0 and hint in out

    code, out, err = run_cli(capsys, *board, "--format", "json")
    assert code == 0 and json.loads(out) == [] and hint in err  # stdout stays the data


def test_an_unknown_race_type_lists_the_choices(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    with pytest.raises(SystemExit) as exited:  # argparse's own usage error
        main(["leaderboard", "--db", db, "--race-type", "drag-race"])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert "time-trial" in err and "object-avoidance" in err and "head-to-bot" in err


def test_a_race_with_a_presets_rules_is_recorded_on_that_race_types_board(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = str(tmp_path / "league.db")
    race = ("--race", "reference", "--track", TRACK, "--window", "10", "--record", "--db", db)

    code, out, err = run_cli(capsys, *race, "--rules", "object-avoidance", "--json")

    assert code == 0, err
    document = json.loads(out)
    assert document["rules"]["race_type"] == "object_avoidance"
    assert document["races"][0]["rules"]["race_type"] == "object_avoidance"
    code, out, err = run_cli(
        capsys, "leaderboard", "--db", db, "--track", TRACK, "--format", "json"
    )
    assert code == 0 and json.loads(out) == []  # nothing on the time trials' board
    boxes = ("--race-type", "object-avoidance", "--format", "json")
    code, out, err = run_cli(capsys, "leaderboard", "--db", db, "--track", TRACK, *boxes)
    assert [row["id"] for row in json.loads(out)] == document["recorded"]


def test_rules_name_a_preset_or_a_file(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_cli(capsys, "--race", "reference", "--rules", "boxes-please")
    assert code == 2
    assert err == (
        "racer-tui: there is no rules file or preset called 'boxes-please'; give a rules YAML "
        "file or one of the presets: league, physical, practice, object-avoidance, "
        "head-to-bot, droa, head-to-head.\n"  # --race also races models together
    )


def test_a_night_opened_with_the_object_avoidance_preset_keeps_it(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = str(tmp_path / "league.db")
    for how in (("--preset", "object-avoidance"), ("--rules", "object-avoidance")):
        code, out, err = run_cli(
            capsys, "night", "new", "--db", db, "--track", TRACK, "--name", how[0][2:], *how
        )
        assert code == 0, err
        assert "Rules (frozen): object avoidance (3 boxes): 4:00 window" in out

    code, out, _ = run_cli(capsys, "night", "list", "--db", db, "--json")
    nights = json.loads(out)
    assert [(n["name"], n["race_type"]) for n in nights] == [
        ("preset", "object_avoidance"),
        ("rules", "object_avoidance"),
    ]
    assert nights[0]["rules"]["obstacles"] == 3
    with open_league(Path(db)) as league:
        night = get_night(league, "preset")
        record_race(league, race_result("ana", [9.5], rules=night.rules), night.id)
    # A night's board is of the night's race type, with no --race-type to give.
    code, out, err = run_cli(
        capsys, "leaderboard", "--db", db, "--night", "preset", "--format", "json"
    )
    assert code == 0, err
    assert _rows(out) == [(1, "ana", 9.5, "object_avoidance")]
    code, out, _ = run_cli(capsys, "night", "show", "preset", "--db", db)
    assert "Rules: object avoidance (3 boxes): " in out
    code, out, _ = run_cli(capsys, "night", "show", "preset", "--db", db, "--json")
    assert json.loads(out)["race_type"] == "object_avoidance"


def test_an_object_avoidance_models_evaluation_is_submitted_to_that_board(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, db: str
) -> None:
    from sim.deepracer.files import TRAINING_PARAMS, TrainingParams, write_training_params
    from sim.tracks.catalog import resolve_track
    from tests.league.helpers import model_folder

    folder = model_folder(tmp_path / "models", "box-car", laps=(8.5,))
    oval = resolve_track(TRACK)
    params = TrainingParams(oval.name, race_type="OBJECT_AVOIDANCE", track_hash=oval.content_hash)
    write_training_params(folder / TRAINING_PARAMS, params)

    code, out, err = run_cli(capsys, "submit", str(folder), "--racer", "dee", "--db", db)

    assert code == 0, err
    assert out.startswith(f"Submitted box-car for dee on {TRACK} (object avoidance): ")
    boxes = ("--race-type", "object-avoidance", "--format", "json")
    code, out, err = run_cli(capsys, "leaderboard", "--db", db, "--track", TRACK, *boxes)
    assert _rows(out)[0] == (1, "dee", 8.5, "object_avoidance")
    code, out, err = run_cli(
        capsys, "leaderboard", "--db", db, "--track", TRACK, "--format", "json"
    )
    assert "dee" not in {row[1] for row in _rows(out)}


def test_a_race_among_bots_says_its_race_type_and_counts_crashes_per_lap(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, _ = run_cli(
        capsys, "--race", "reference", "--track", "reinvent_base", "--rules", "head-to-bot",
        "--window", "60", "--db", str(tmp_path / "league.db"),
    )  # fmt: skip
    assert code == 0
    # The title wraps at the table's width.
    assert "on reinvent_base, head-to-bot (3 bots at 1 m/s, changing lanes)" in " ".join(
        out.split()
    )
    assert any("crashes" in line and "off-tracks" in line for line in out.splitlines())
    code, out, _ = run_cli(
        capsys, "--race", "reference", "--track", "reinvent_base", "--window", "30",
        "--db", str(tmp_path / "league.db"),
    )  # fmt: skip
    assert code == 0 and "crashes" not in out  # nothing to crash into in a time trial


def test_an_empty_leaderboard_says_how_laps_get_there(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, _ = run_cli(capsys, "leaderboard", "--db", str(tmp_path / "empty.db"))
    assert code == 0
    assert "No laps in this league yet: record a race with racer-tui --race" in out


def test_a_lap_whose_car_was_turned_round_says_so() -> None:
    plain = race_result("ana", [10.0, 10.5])
    first = replace(plain.laps[0], reversals=1, penalty_seconds=3.0, time_seconds=13.0)
    console = Console(width=100, record=True)
    track = resolve_track(TRACK)
    console.print(race_table(plain, track))
    assert "turned round" not in console.export_text()
    console.print(race_table(replace(plain, laps=(first, plain.laps[1])), track))
    turned = [line for line in console.export_text().splitlines() if "13.000" in line]
    assert turned and turned[0].split("│")[6].strip() == "1"

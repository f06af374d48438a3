"""The league from the command line: submit, leaderboard in every format, a league night
from `night new` to `season show`, corrections, and one-sentence errors with exit 2."""

from __future__ import annotations

import csv
import io
import json
import re
import sqlite3
from pathlib import Path

import pytest

from league.migrations import SCHEMA_VERSION
from racer_tui.cli.main import main
from tests.league.helpers import model_folder

MARKUP_NAME = "[bold red]x[/]"


@pytest.fixture(autouse=True)
def wide_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "160")  # rich tables wide enough that no name wraps


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def db(tmp_path: Path) -> str:
    return str(tmp_path / "league.db")


@pytest.fixture
def submitted(capsys: pytest.CaptureFixture[str], tmp_path: Path, db: str) -> str:
    """Three racers on one track, one of them with a name that looks like markup."""
    for racer, laps in ((MARKUP_NAME, (11.0, 11.4)), ("bob", (11.2, 11.3, 11.1)), ("cy", (13.0,))):
        folder = model_folder(tmp_path / racer.replace("/", "_"), f"car-{len(laps)}", laps=laps)
        code, out, err = run_cli(capsys, "submit", str(folder), "--racer", racer, "--db", db)
        assert code == 0, err
        assert out.startswith("Submitted car-")
    return db


def test_leaderboard_json(capsys: pytest.CaptureFixture[str], submitted: str) -> None:
    code, out, _ = run_cli(capsys, "leaderboard", "--db", submitted, "--format", "json")
    assert code == 0
    rows = json.loads(out)
    assert [(r["rank"], r["racer"], r["best_lap"], r["laps"]) for r in rows] == [
        (1, MARKUP_NAME, 11.0, 2),
        (2, "bob", 11.1, 3),
        (3, "cy", 13.0, 1),
    ]
    assert all(len(r["id"]) == 26 and r["kind"] == "submission" for r in rows)


def test_leaderboard_table_prints_names_literally(
    capsys: pytest.CaptureFixture[str], submitted: str
) -> None:
    code, out, _ = run_cli(capsys, "leaderboard", "--db", submitted)
    assert code == 0
    assert MARKUP_NAME in out
    for title in ("rank", "racer", "model", "best lap", "average", "laps", "off-tracks"):
        assert title in out


def test_leaderboard_csv_and_markdown(capsys: pytest.CaptureFixture[str], submitted: str) -> None:
    _, out, _ = run_cli(capsys, "leaderboard", "--db", submitted, "--format", "csv")
    table = list(csv.DictReader(io.StringIO(out)))
    assert [row["racer"] for row in table] == [MARKUP_NAME, "bob", "cy"]
    assert table[1]["average"] == "11.200" and table[1]["laps"] == "3"
    assert table[0]["submitted"].endswith("Z")
    _, out, _ = run_cli(capsys, "leaderboard", "--db", submitted, "--format", "markdown")
    lines = out.splitlines()
    assert lines[0].startswith("| rank | racer | model |")
    assert lines[1].startswith("| ---: | --- |")
    assert "\\[bold red\\]x\\[/\\]" in lines[2]


def test_leaderboard_by_average_sort_filter_and_limit(
    capsys: pytest.CaptureFixture[str], submitted: str
) -> None:
    def ranked(*args: str) -> list[str]:
        code, out, err = run_cli(
            capsys, "leaderboard", "--db", submitted, "--format", "json", *args
        )
        assert code == 0, err
        return [row["racer"] for row in json.loads(out)]

    assert ranked("--by", "average") == ["bob", MARKUP_NAME, "cy"]  # only bob drove 3 laps
    assert ranked("--sort", "laps", "--reverse") == ["bob", MARKUP_NAME, "cy"]
    assert ranked("--sort", "racer") == [MARKUP_NAME, "bob", "cy"]
    assert ranked("--racer", "cy") == ["cy"]
    assert ranked("--limit", "1") == [MARKUP_NAME]
    assert ranked("--track", "beginner-oval", "--limit", "2") == [MARKUP_NAME, "bob"]
    assert ranked("--track", "speedway") == []


def test_submitting_the_real_deepracer_downloads(
    capsys: pytest.CaptureFixture[str], deepracer_dir: Path, db: str
) -> None:
    """On a fresh install: no track imported, the official track named as racers know it."""
    for folder, racer, track in (
        ("drfc-model", "drfc fan", "reinvent_base"),
        ("console-logs", "console fan", "re:Invent 2018"),
    ):
        code, out, err = run_cli(
            capsys,
            "submit",
            str(deepracer_dir / folder),
            "--racer",
            racer,
            "--track",
            track,
            "--db",
            db,
            "--json",
        )
        assert code == 0, err
        assert json.loads(out)["laps"] == 3
    _, out, _ = run_cli(
        capsys, "leaderboard", "--db", db, "--format", "json", "--track", "RE:INVENT 2018"
    )
    assert [row["racer"] for row in json.loads(out)] == ["drfc fan", "console fan"]


def test_a_bad_submission_is_one_sentence_and_writes_nothing(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, db: str
) -> None:
    folder = model_folder(tmp_path)
    bad = folder / "metrics" / "EvaluationMetrics-20240501120000.json"
    bad.write_text('{"metrics": [{"completion_percentage": "lots"}]}')
    code, out, err = run_cli(capsys, "submit", str(folder), "--racer", "ana", "--db", db)
    assert code == 2 and out == ""
    assert err.startswith("racer-tui: ") and str(bad) in err and err.count("\n") == 1
    assert sqlite3.connect(db).execute("SELECT count(*) FROM submissions").fetchone()[0] == 0


def test_a_newer_database_is_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "future.db"
    conn = sqlite3.connect(path)
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 5}")
    conn.commit()
    conn.close()
    code, _, err = run_cli(capsys, "leaderboard", "--db", str(path))
    assert code == 2 and "newer" in err and "Traceback" not in err


def test_a_league_night_from_the_command_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, db: str
) -> None:
    rules = tmp_path / "rules.yaml"
    rules.write_text("window_seconds: 15\nmax_offtracks_per_lap: 3\n")
    assert run_cli(capsys, "season", "new", "2024", "--points", "10,5", "--db", db)[0] == 0
    code, out, err = run_cli(
        capsys,
        "night",
        "new",
        "--track",
        "beginner-oval",
        "--rules",
        str(rules),
        "--name",
        "Opening",
        "--season",
        "2024",
        "--db",
        db,
    )
    assert code == 0, err
    assert "0:15 window" in out
    for racer in ("ana", MARKUP_NAME):
        code, _, err = run_cli(
            capsys, "night", "add", "Opening", "--racer", racer, "--model", "reference", "--db", db
        )
        assert code == 0, err
    code, out, _ = run_cli(capsys, "night", "draw", "Opening", "--seed", "4", "--db", db)
    assert out.count("heat ") == 2
    code, out, err = run_cli(capsys, "night", "run", "Opening", "--db", db)
    assert code == 0, err
    assert out.count("best lap") == 2 and MARKUP_NAME in out

    code, out, _ = run_cli(capsys, "night", "show", "Opening", "--db", db, "--json")
    shown = json.loads(out)
    assert shown["rules"]["window_seconds"] == 15.0
    assert all(heat["race_id"] for heat in shown["heats"])
    code, out, _ = run_cli(
        capsys, "night", "close", "Opening", "--by", "host", "--db", db, "--json"
    )
    standings = json.loads(out)
    assert [s["points"] for s in standings] == [10, 5]
    winner = standings[0]["racer_name"]
    code, out, _ = run_cli(capsys, "season", "show", "2024", "--db", db, "--json")
    season = json.loads(out)
    assert season["nights"] == 1
    assert (season["standings"][0]["racer_name"], season["standings"][0]["points"]) == (winner, 10)
    code, out, _ = run_cli(capsys, "season", "show", "2024", "--db", db)
    assert MARKUP_NAME in out
    code, out, _ = run_cli(
        capsys, "leaderboard", "--night", "Opening", "--db", db, "--format", "json"
    )
    assert {row["kind"] for row in json.loads(out)} == {"race"}
    code, _, err = run_cli(
        capsys, "night", "add", "Opening", "--racer", "late", "--model", "reference", "--db", db
    )
    assert code == 2 and "closed" in err


def test_corrections_from_the_command_line(
    capsys: pytest.CaptureFixture[str], submitted: str
) -> None:
    _, out, _ = run_cli(capsys, "leaderboard", "--db", submitted, "--format", "json")
    leader = json.loads(out)[0]
    code, out, err = run_cli(
        capsys,
        "correct",
        "lap",
        leader["id"],
        "1",
        "--reason",
        "off the track",
        "--by",
        "steward",
        "--db",
        submitted,
    )
    assert code == 0, err
    code, out, err = run_cli(
        capsys, "racer", "rename", "bob", "Robert", "--by", "bob", "--db", submitted
    )
    assert code == 0, err
    _, out, _ = run_cli(capsys, "leaderboard", "--db", submitted, "--format", "json")
    assert [(r["racer"], r["best_lap"]) for r in json.loads(out)] == [
        ("Robert", 11.1),
        (MARKUP_NAME, 11.4),
        ("cy", 13.0),
    ]
    _, out, _ = run_cli(capsys, "correct", "list", "--db", submitted, "--json")
    assert [c["kind"] for c in json.loads(out)] == ["disqualify_lap", "rename_racer"]
    code, _, err = run_cli(
        capsys,
        "correct",
        "lap",
        leader["id"],
        "9",
        "--reason",
        "x",
        "--by",
        "steward",
        "--db",
        submitted,
    )
    assert code == 2 and "has no lap 9" in err


def test_a_new_night_defaults_to_the_reinvent_2018_track(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    code, _, err = run_cli(capsys, "night", "new", "--name", "Default", "--db", db)
    assert code == 0, err
    _, out, _ = run_cli(capsys, "night", "show", "Default", "--db", db, "--json")
    assert json.loads(out)["track"] == "reinvent_base"


def test_a_lap_count_night_races_each_heat_to_its_laps(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    def cli(*args: str) -> tuple[int, str, str]:
        return run_cli(capsys, "night", *args, "--db", db)

    code, _, err = cli("new", "--track", "beginner-oval", "--name", "Sprint", "--laps", "0")
    assert code == 2 and err.startswith("racer-tui: --laps: lap_count must be a whole number")
    code, _, err = cli("new", "--name", "Sprint", "--date", "next friday")
    assert code == 2 and "'next friday' is not a night's date; write it as YYYY-MM-DD" in err
    code, out, err = cli(
        "new", "--track", "beginner-oval", "--name", "Sprint", "--laps", "2", "--date",
        "2027-01-08", "--preset", "physical",
    )  # fmt: skip
    assert code == 0, err
    assert "on beginner-oval, 2027-01-08." in out
    assert "race of 2 laps within 4:00, no time added per off-track, at most 3 off-tracks" in out
    for racer in ("ana", "bob"):
        assert cli("add", "Sprint", "--racer", racer, "--model", "reference")[0] == 0
    assert cli("draw", "Sprint")[0] == 0
    code, _, err = cli("run", "Sprint")
    assert code == 0, err
    _, out, _ = cli("show", "Sprint", "--json")
    shown = json.loads(out)
    assert shown["rules"]["lap_count"] == 2 and shown["held_on"] == "2027-01-08"
    _, out, _ = run_cli(capsys, "leaderboard", "--night", "Sprint", "--db", db, "--format", "json")
    rows = json.loads(out)
    # A 4-minute window would have given dozens of laps on the oval; each heat drove two.
    assert [row["laps"] for row in rows] == [2, 2]


def test_a_host_withdraws_moves_and_deletes_from_the_command_line(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    def cli(*args: str) -> tuple[int, str, str]:
        return run_cli(capsys, "night", *args, "--db", db)

    assert cli("new", "--track", "beginner-oval", "--name", "Fri")[0] == 0
    for racer in ("ana", "bob", "cy"):
        assert cli("add", "Fri", "--racer", racer, "--model", "reference")[0] == 0
    assert cli("add", "Fri", "--racer", "ana", "--model", "physical")[0] == 0
    code, _, err = cli("withdraw", "Fri", "ana")
    assert code == 2 and "entered 2 cars (reference, physical); give --model too" in err
    code, out, err = cli("withdraw", "Fri", "ana", "--model", "physical", "--by", "host")
    assert code == 0 and "Withdrew ana (physical) from Fri." in out, err
    code, out, _ = cli("draw", "Fri", "--seed", "2")
    last = out.strip().splitlines()[-1].split()[2]
    code, out, err = cli("move", "Fri", last, "--to", "1")
    assert code == 0, err
    assert out.splitlines()[1].startswith(f"1. heat 1: {last} ")
    assert "--to must be from 1 to 3" in cli("move", "Fri", last, "--to", "5")[2]
    code, _, err = cli("delete", "Fri")
    assert code == 0, err
    code, out, _ = cli("list", "--json")
    assert json.loads(out) == []


def test_night_add_says_the_physical_rules_note_for_the_first_physical_car_only(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    """A fleet of physical cars entered one by one heard the same note for each (the host
    walk); it is said once, for the first."""
    from league.nights import PHYSICAL_RULES_NOTE

    def notes(racer: str, model: str) -> list[str]:
        code, out, err = run_cli(
            capsys, "night", "add", "Fri", "--racer", racer, "--model", model, "--db", db
        )
        assert code == 0, err
        return [line for line in out.splitlines() if line.startswith("Note: ")]

    assert (
        run_cli(capsys, "night", "new", "--track", "beginner-oval", "--name", "Fri", "--db", db)[0]
        == 0
    )
    assert notes("ana", "reference") == []
    assert notes("bob", "physical:red") == [f"Note: {PHYSICAL_RULES_NOTE}"]
    assert notes("cy", "physical:blue") == []


def test_a_night_run_killed_mid_way_keeps_its_heats_and_runs_the_rest(tmp_path: Path) -> None:
    """Each heat is recorded in one transaction as it finishes: a killed `night run`
    leaves whole heats and waiting ones, and running it again finishes the night."""
    import os
    import signal
    import subprocess
    import sys

    from league.nights import add_entrant, draw_heats, get_night, heats, new_night, pending_heats
    from league.opening import open_league
    from sim.tracks.catalog import resolve_track

    db = str(tmp_path / "kill.db")
    env = {**os.environ, "RACER_TUI_HOME": str(tmp_path / "home")}
    command = [sys.executable, "-m", "racer_tui.cli.main", "night", "run", "Fri", "--db", db]
    with open_league(Path(db)) as league:
        night = new_night(league, resolve_track("reInvent2019_track"), name="Fri")
        for number in range(8):
            add_entrant(league, night, f"r{number}", "reference")
        draw_heats(league, night, seed=1)
    run = subprocess.Popen(
        command,
        env=env,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert run.stdout is not None
    first = run.stdout.readline()
    run.send_signal(signal.SIGKILL)
    run.wait()
    assert first.startswith("heat ")
    with open_league(Path(db)) as league:
        night = get_night(league, "Fri")
        raced = [heat for heat in heats(league, night) if heat.race_id is not None]
        assert 1 <= len(raced) <= 8
        laps = league.query("SELECT count(*) FROM race_laps")[0][0]
        entries = league.query("SELECT count(*) FROM entries WHERE night_id = ?", (night.id,))
        assert entries[0][0] == len(raced) and laps > 0  # whole races, cache and all
        waiting = len(pending_heats(league, night))
    assert len(raced) + waiting == 8
    if waiting:
        subprocess.run(command, env=env, capture_output=True, check=True)
    with open_league(Path(db)) as league:
        night = get_night(league, "Fri")
        assert pending_heats(league, night) == []
        assert len({heat.entrant.racer for heat in heats(league, night)}) == 8


def test_a_physical_heat_passed_over_keeps_every_heat_number_true(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # The host walk: `night run` said "heat 3" for two racers once a physical car's heat
    # was passed over, and the draw's numbers no longer matched `night show`.
    db = str(tmp_path / "league.db")
    night = ("--db", db)
    assert (
        run_cli(capsys, "night", "new", "--track", "beginner-oval", "--name", "N", *night)[0] == 0
    )
    for racer, model in (("bob", "reference"), ("cara", "physical"), ("dave", "reference")):
        code, _, err = run_cli(
            capsys, "night", "add", "N", "--racer", racer, "--model", model, *night
        )
        assert code == 0, err
    code, drawn, err = run_cli(capsys, "night", "draw", "N", "--seed", "2", *night)
    assert code == 0, err
    assert "A physical car's heat waits for its timekeeper" in drawn
    code, ran, err = run_cli(capsys, "night", "run", "N", *night)
    assert code == 0, err
    said = {racer: number for number, racer in re.findall(r"^heat (\d+): (\w+)", ran, re.M)}
    code, out, _ = run_cli(capsys, "night", "show", "N", "--json", *night)
    shown = {heat["racer"]: str(heat["position"]) for heat in json.loads(out)["heats"]}
    assert said == shown  # one number per racer, the running order's
    assert len(set(said.values())) == 3 and said["cara"] == "3"

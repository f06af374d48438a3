"""`racer-tui --race`: headless time trials, a table or one JSON document, exit codes 0/2/1."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from racer_tui.cli import race_commands
from racer_tui.cli.main import main
from sim.physics.reference_driver import reference_lap
from sim.race.trace import RaceTrace
from sim.tracks.catalog import resolve_track

SHORT = ("--track", "hairpin-circuit", "--window", "20")


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def trained_model() -> str:
    """A garage model with a (freshly initialised) policy file: it can race."""
    pytest.importorskip("torch")
    from sim.garage.options import new_model
    from sim.training.policy import build_network, save_policy

    folder = new_model("quick-car")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    return folder.name


def test_reference_race_prints_a_lap_table(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", *SHORT, "--racer", "[bold]Ada")
    assert code == 0, err
    assert "[bold]Ada (reference) on hairpin-circuit" in out  # names are never markup
    standing_start = reference_lap(resolve_track("hairpin-circuit")).lap_time
    assert f"{standing_start:.3f}" in out
    assert "2 laps, 2 counting, 0 off-tracks" in out
    assert "Standings" not in out  # one entrant: no standings table


def test_json_is_the_only_thing_on_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "--race", "reference", "reference", *SHORT, "--json")
    assert code == 0
    document = json.loads(out)
    assert document["track"]["name"] == "hairpin-circuit"
    assert document["rules"]["window_seconds"] == 20.0
    first, second = document["races"]
    assert [lap["time_seconds"] for lap in first["laps"]] == [
        lap["time_seconds"] for lap in second["laps"]
    ]
    assert first["laps"][0]["valid"] is True
    assert first["scoring"]["value"] == pytest.approx(first["best_lap_seconds"])
    # Equal races: the earlier result ranks first.
    assert [row["result_id"] for row in document["standings"]] == [
        first["result_id"],
        second["result_id"],
    ]
    assert document["standings"][0]["position"] == 1
    assert document["recorded"] == []


def test_rule_options_override_the_rules_file(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    rules = tmp_path / "night.yaml"
    rules.write_text("window_seconds: 100\npenalty_seconds: 5\nranking: total_time\n")
    code, out, err = run_cli(
        capsys,
        "--race",
        "reference",
        "--track",
        "hairpin-circuit",
        "--rules",
        str(rules),
        "--window",
        "30",
        "--max-offtracks",
        "unlimited",
        "--ranking-laps",
        "2",
        "--json",
    )
    assert code == 0, err
    document = json.loads(out)
    assert document["rules"] == {
        "window_seconds": 30.0,
        "penalty_seconds": 5.0,
        "max_offtracks_per_lap": "unlimited",
        "ranking": "total_time",
        "ranking_laps": 2,
        "collision_penalty_seconds": 5.0,
    }
    laps = document["races"][0]["laps"]
    assert document["races"][0]["scoring"]["value"] == pytest.approx(
        laps[0]["time_seconds"] + laps[1]["time_seconds"]
    )


def test_several_models_print_standings(
    capsys: pytest.CaptureFixture[str], trained_model: str
) -> None:
    code, out, err = run_cli(capsys, "--race", trained_model, "reference", *SHORT)
    assert code == 0, err
    assert "Standings" in out
    standings = out[out.index("Standings") :]
    # The reference driver laps; an untrained network does not: it ranks last.
    assert standings.index("reference") < standings.index(trained_model)


def test_a_bundle_races_under_its_model_name(
    capsys: pytest.CaptureFixture[str], trained_model: str, tmp_path: Path
) -> None:
    from sim.garage.bundle import export_bundle
    from sim.garage.folder import open_model

    bundle = export_bundle(open_model(trained_model), tmp_path / "car")
    code, out, err = run_cli(capsys, "--race", str(bundle), *SHORT, "--json")
    assert code == 0, err
    race = json.loads(out)["races"][0]
    assert race["model_name"] == trained_model
    assert race["racer"] == trained_model
    assert race["model_hash"] == open_model(trained_model).content_hash()


def test_traces_are_written_as_sim_trace_csv(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    folder = tmp_path / "traces"
    code, out, _ = run_cli(
        capsys, "--race", "reference", *SHORT, "--trace-dir", str(folder), "--json"
    )
    assert code == 0
    race = json.loads(out)["races"][0]
    path = Path(race["trace_file"])
    assert path.parent == folder and path.name == f"{race['result_id']}.csv"
    assert len(RaceTrace.read_csv(path)) == 301


def test_record_stores_the_results_in_the_league(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", *SHORT, "--record", "--json")
    assert code == 0, err
    document = json.loads(out)
    race_id = document["races"][0]["result_id"]
    assert document["recorded"] == [race_id]
    from league.opening import open_league
    from league.races import race_result, race_trace

    with open_league() as league:
        stored = race_result(league, race_id)
        trace = race_trace(league, race_id)
    assert [lap.time_seconds for lap in stored.laps] == [
        lap["time_seconds"] for lap in document["races"][0]["laps"]
    ]
    assert trace is not None and len(trace) == 301


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--race", "no-such-model", *SHORT), "no-such-model"),
        (("--race", "reference", "--track", "no-such-track"), "no-such-track"),
        (("--race", "missing.racer-bundle", *SHORT), "missing.racer-bundle"),
        (("--race", "reference", *SHORT, "--penalty", "-2"), "--penalty"),
        (("--race", "reference", *SHORT, "--max-offtracks", "few"), "--max-offtracks"),
        (("--race", "reference", "--track", "hairpin-circuit", "--window", "2"), "--window"),
        (("--race", "reference", *SHORT, "--racer", "two\nlines"), "racer name"),
        (("--race", "reference", *SHORT, "--seed", "-1"), "--seed"),
        (("--race", "reference", *SHORT, "--laps", "0"), "--laps"),
        (
            ("--race", "reference", *SHORT, "--laps", "2", "--ranking", "total_time"),
            "make --ranking-laps (ranking_laps) at most 2 or --laps (lap_count) larger",
        ),
    ],
)
def test_bad_input_is_one_sentence_and_exit_2(
    capsys: pytest.CaptureFixture[str], args: tuple[str, ...], message: str
) -> None:
    code, out, err = run_cli(capsys, *args)
    assert code == 2
    assert out == ""
    assert err.startswith("racer-tui: ") and message in err
    assert "Traceback" not in err and err.count("\n") == 1


def test_a_bad_rules_file_names_the_key(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rules = tmp_path / "rules.yaml"
    rules.write_text("window_seconds: 240\noff_track_penalty: 3\n")
    code, _, err = run_cli(capsys, "--race", "reference", *SHORT, "--rules", str(rules))
    assert code == 2
    assert "off_track_penalty" in err and str(rules) in err


def test_an_untrained_model_is_a_user_error(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("torch")
    from sim.garage.options import new_model

    new_model("untrained-car")
    code, _, err = run_cli(capsys, "--race", "untrained-car", *SHORT)
    assert code == 2
    assert "untrained-car" in err and "train" in err


def test_missing_arguments_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_cli(capsys, "--race")
    assert code == 2
    assert "--race" in err


def test_races_default_to_the_reinvent_2018_track(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", "--window", "20", "--json")
    assert code == 0, err
    assert json.loads(out)["track"]["name"] == "reinvent_base"


def test_help_lists_the_options(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "--race", "--help")
    assert code == 0
    for option in ("--track", "--racer", "--rules", "--max-offtracks", "--record", "--json"):
        assert option in out


def test_an_unexpected_failure_exits_1(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("the physics fell over")

    monkeypatch.setattr(race_commands, "run_race", broken)
    code, out, err = run_cli(capsys, "--race", "reference", *SHORT)
    assert code == 1
    assert out == ""
    assert "the physics fell over" in err and "Traceback" not in err


def test_the_race_path_imports_neither_textual_nor_torch() -> None:
    script = (
        "import sys\n"
        "from racer_tui.cli.main import main\n"
        "code = main(['--race', 'reference', '--track', 'hairpin-circuit', '--window', '10',"
        " '--json'])\n"
        "heavy = sorted(m for m in ('textual', 'torch') if m in sys.modules)\n"
        "print(code, heavy, file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    assert done.stderr.strip() == "0 []"
    assert json.loads(done.stdout)["races"][0]["model_name"] == "reference"


def test_one_league_file_for_every_command_with_db(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from league.store import default_db_path

    season = tmp_path / "season-2.db"
    code, out, err = run_cli(
        capsys, "--race", "reference", *SHORT, "--record", "--db", str(season), "--json"
    )
    assert code == 0, err
    race_id = json.loads(out)["recorded"][0]
    assert season.is_file() and not default_db_path().exists()

    # The top-level --db (the app's) reaches every command through RACER_TUI_LEAGUE.
    monkeypatch.setenv("RACER_TUI_LEAGUE", "")  # unset, and restored after the test
    code, out, err = run_cli(capsys, "--db", str(season), "leaderboard", "--format", "json")
    assert code == 0, err
    assert [row["id"] for row in json.loads(out)] == [race_id]
    assert default_db_path() == season

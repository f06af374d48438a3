"""`racer-tui --race A B --rules head-to-head`: the models race together, the table or one
JSON document says who won and what happened, and `--record` keeps it in the league; what a
league cannot take is refused in one sentence, everywhere a head-to-head race's rules could
enter it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from league.errors import LeagueError
from league.head_to_heads import head_to_head_races
from league.nights import new_night
from league.opening import open_league
from racer_tui.cli.main import main
from sim.deepracer.files import DeepRacerFileError, TrainingParams
from sim.physics.objects.reading import race_settings
from sim.race.rules import HEAD_TO_HEAD_RULES, rules_from_mapping
from sim.tracks.catalog import resolve_track

H2H = ("--rules", "head-to-head", "--track", "hairpin-circuit")


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_two_cars_race_and_the_table_names_the_winner(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", "reference", *H2H)
    assert code == 0, err
    assert "Head-to-head on hairpin-circuit, 3 laps" in out
    assert "reference won (head-to-head: 3 laps within 4:00, first past the line" in out
    rows = [line for line in out.splitlines() if line.startswith("│")]
    assert rows[0].split("│")[1].strip() == "1" and rows[1].split("│")[1].strip() == "2"


def test_json_gives_every_car_its_place_laps_and_gap(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", "reference", *H2H, "--json")
    assert code == 0, err
    document = json.loads(out)
    assert document["race"] == "head-to-head"
    assert document["rules"]["race_type"] == "head_to_model"
    first, second = document["cars"]
    assert (first["position"], first["grid"], first["laps_completed"]) == (1, 1, 3)
    assert first["finished_at_seconds"] == pytest.approx(
        sum(lap["time_seconds"] for lap in first["laps"])
    )
    assert second["finished_at_seconds"] is None and second["gap_seconds"] > 0
    # The same race again: deterministic.
    _, again, _ = run_cli(capsys, "--race", "reference", "reference", *H2H, "--json")
    assert [car["laps"] for car in json.loads(again)["cars"]] == [first["laps"], second["laps"]]


def test_record_keeps_the_race_in_the_league_as_one_record(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = tmp_path / "league.db"
    args = ("--race", "reference", "reference", *H2H, "--record", "--db", str(db))
    code, out, err = run_cli(capsys, *args, "--json")
    assert code == 0, err
    document = json.loads(out)
    [race_id] = document["recorded"]
    with open_league(db) as league:
        [recorded] = head_to_head_races(league)
    assert recorded.id == race_id
    assert [place.laps_completed for place in recorded.places] == [
        car["laps_completed"] for car in document["cars"]
    ]
    code, out, err = run_cli(capsys, *args)  # the table says so too
    assert code == 0, err
    assert out.rstrip().endswith("recorded the head-to-head race in the league.")


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ((), "takes 2 to 6 models, not 1"),
        (("reference",) * 6, "takes 2 to 6 models, not 7"),
        (("reference", "--racer", "Ada"), "--racer: each car of a head-to-head race is its"),
    ],
)
def test_what_a_head_to_head_race_cannot_take_is_one_sentence(
    capsys: pytest.CaptureFixture[str], extra: tuple[str, ...], words: str
) -> None:
    code, out, err = run_cli(capsys, "--race", "reference", *extra, *H2H)
    assert code == 2 and out == ""
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_a_night_a_league_record_and_a_training_refuse_head_to_head_rules(
    tmp_path: Path,
) -> None:
    track = resolve_track("hairpin-circuit")
    with open_league() as league, pytest.raises(LeagueError, match="heats are time trials"):
        new_night(league, track, rules=HEAD_TO_HEAD_RULES)
    # Rules files name it as the race type: read, and kept apart from time trials.
    rules = rules_from_mapping({"race_type": "head_to_model", "lap_count": 2})
    assert rules.race_words == "head-to-head"
    params = TrainingParams.from_mapping(
        {"WORLD_NAME": "reInvent2019_wide", "RACE_TYPE": "HEAD_TO_MODEL"}, "training_params.yaml"
    )
    with pytest.raises(DeepRacerFileError, match="DeepRacer does not train"):
        race_settings(params)


def test_night_new_does_not_offer_the_head_to_head_preset(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, err = run_cli(capsys, "night", "new", "--track", "hairpin-circuit", *H2H[:2])
    assert code == 2
    assert "no rules file or preset called 'head-to-head'" in err


def test_a_car_of_a_head_to_head_race_is_not_recorded_as_a_time_trial() -> None:
    from league.races import record_race
    from sim.race.driver import reference_driver
    from sim.race.head_to_head import Entry, run_head_to_head

    track = resolve_track("hairpin-circuit")
    driver = reference_driver(track)
    race = run_head_to_head(track, HEAD_TO_HEAD_RULES, [Entry("a", driver), Entry("b", driver)])
    with open_league() as league, pytest.raises(LeagueError, match="head-to-head race"):
        record_race(league, race.winner.result)


def test_a_garage_model_races_itself_in_one_batch(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("torch")
    from sim.garage.options import new_model
    from sim.training.policy import build_network, save_policy

    folder = new_model("twin")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    args = ("--race", "twin", "twin", *H2H, "--window", "20", "--json")
    code, out, err = run_cli(capsys, *args)
    assert code == 0, err
    cars = json.loads(out)["cars"]
    assert [car["model_name"] for car in cars] == ["twin", "twin"]
    assert sorted(car["grid"] for car in cars) == [1, 2]
    _, again, _ = run_cli(capsys, *args)
    assert [car["distance_m"] for car in json.loads(again)["cars"]] == [
        car["distance_m"] for car in cars
    ]


def test_trace_dir_writes_a_sim_trace_for_each_car(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from sim.race.trace import STATUS_CODE, RaceTrace

    folder = tmp_path / "traces"
    args = ("--race", "reference", "reference", *H2H, "--trace-dir", str(folder), "--json")
    code, out, err = run_cli(capsys, *args)
    assert code == 0, err
    cars = json.loads(out)["cars"]
    for car in cars:
        trace = RaceTrace.read_csv(Path(car["trace_file"]))
        assert Path(car["trace_file"]).parent == folder
        # One row on the grid and one a step until the winner's last lap ended the race.
        assert len(trace) == round(json.loads(out)["clock_seconds"] * 15) + 1
        laps_done = int((trace.status == STATUS_CODE["lap_complete"]).sum())
        assert laps_done == car["laps_completed"]

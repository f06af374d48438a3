"""No lap under the track's floor enters the league: not by `racer-tui submit` of a
hand-edited evaluation, not as a recorded race or a night's heat, not timed by hand
(issue 41). Honest laps, racer-tui's and DeepRacer's own, still are."""

from __future__ import annotations

import json
import sqlite3
from dataclasses import replace
from pathlib import Path

import pytest

from league.errors import LeagueError
from league.races import record_race
from league.records import record_body
from league.store import League
from league.submissions import submit_model
from league.sync.errors import RecordInvalidError
from league.sync.record import make_record
from league.sync.validate import check_record
from league.timekeeper.heat import TimekeeperError, TimekeptHeat, physical_floor
from racer_tui.cli.main import main
from sim.coach.plausible import fastest_possible_lap
from sim.foundation.ids import new_id
from sim.physics.labels import PHYSICAL
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from tests.league.helpers import model_folder, race_result

REINVENT = "reinvent_base"


@pytest.fixture(scope="module")
def floor() -> float:
    return fastest_possible_lap(resolve_track(REINVENT))


@pytest.mark.parametrize("forged", [3.9, 1.0])
def test_a_hand_edited_evaluation_is_refused_by_submit_in_one_sentence(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, forged: float, floor: float
) -> None:
    folder = model_folder(tmp_path, laps=(12.4, forged, 12.9), track=REINVENT)
    db = str(tmp_path / "league.db")
    code = main(["submit", str(folder), "--racer", "ana", "--db", db])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err == (
        f"racer-tui: EvaluationMetrics-20240501120000.json: lap 2 of {forged:.3f} s is faster "
        f"than any DeepRacer car can drive {REINVENT} (no lap under {floor:.3f} s is possible "
        "there: under DeepRacer's rules at 4 m/s), so it cannot be submitted.\n"
    )
    assert sqlite3.connect(db).execute("SELECT count(*) FROM submissions").fetchone()[0] == 0


def test_real_deepracer_evaluations_are_still_submitted(
    deepracer_dir: Path, league: League, floor: float
) -> None:
    for folder in ("drfc-model", "console-logs"):
        submission, outcome = submit_model(
            league, str(deepracer_dir / folder), "ana", track=REINVENT
        )
        assert not outcome.duplicate and submission.best_lap is not None
        assert submission.best_lap > floor


@pytest.mark.parametrize("forged", [3.9, 1.0])
def test_a_pulled_submission_under_the_floor_is_refused(
    tmp_path: Path, league: League, forged: float, floor: float
) -> None:
    folder = model_folder(tmp_path, laps=(12.4, 12.9), track=REINVENT)
    _, outcome = submit_model(league, str(folder), "ana")
    body = record_body(league, "submissions", outcome.submission_id)
    check_record(make_record("submission", outcome.submission_id, body))  # honest: passes
    body["laps"] = [{**body["laps"][0], "time_seconds": forged}, *body["laps"][1:]]
    with pytest.raises(RecordInvalidError) as refused:
        check_record(make_record("submission", outcome.submission_id, body))
    assert str(refused.value) == (
        f"its lap 1 of {forged:.3f} s is faster than any car can go round that track (no lap "
        f"under {floor:.3f} s is possible there: under DeepRacer's rules at 4 m/s)"
    )


def test_a_race_of_impossible_laps_is_not_recorded(league: League, floor: float) -> None:
    track = resolve_track(REINVENT)
    forged = race_result("ana", [4.1, 4.1, 4.1], track=track)
    with pytest.raises(LeagueError) as refused:
        record_race(league, forged)
    assert str(refused.value) == (
        f"The race was not recorded: lap 1 of 4.100 s is faster than any DeepRacer car can "
        f"drive {REINVENT} (no lap under {floor:.3f} s is possible there: under DeepRacer's "
        "rules at 4 m/s)."
    )
    assert league.query_one("SELECT count(*) FROM races")[0] == 0
    # Signed by its own racer, pulled: refused the same way.
    record_race(league, honest := race_result("ana", [12.0, 11.8], track=track))
    body = record_body(league, "races", honest.result_id)
    body["laps"] = [
        {**lap, "time_seconds": 4.1, "raw_seconds": 4.1, "penalty_seconds": 0.0}
        for lap in body["laps"]
    ]
    with pytest.raises(RecordInvalidError, match=r"its lap 1 of 4\.100 s is faster than any car"):
        check_record(make_record("race", honest.result_id, body))


def test_the_reference_drivers_race_is_recorded(league: League, floor: float) -> None:
    result = run_race(resolve_track(REINVENT), RaceRules(window_seconds=20.0), racer="ref")
    assert result.best_lap is not None and result.best_lap.raw_seconds > floor
    assert record_race(league, result) == result.result_id


def test_a_physical_heat_has_a_floor_of_its_own(league: League, floor: float) -> None:
    track = resolve_track(REINVENT)
    lowest = physical_floor(track)
    assert lowest < 3.0 < floor
    heat = TimekeptHeat(RaceRules(window_seconds=60.0), floor_seconds=lowest)
    heat.start_or_pause(0.0)
    with pytest.raises(TimekeeperError) as early:
        heat.capture(2.0)  # a false finish: the lap goes on
    assert str(early.value) == (
        f"A lap of 2.00 s is faster than a real car can drive this track (no lap under "
        f"{lowest:.2f} s), so it was not captured; capture when the car crosses the line."
    )
    heat.capture(3.0)  # under the simulators' floor, over a real car's: a real lap
    heat.did_not_finish(4.5)  # given up 1.5 s in: kept, never counts, never checked
    heat.end(10.0)
    result = heat.result(
        racer="ana", car="physical", car_hash="physical", track_name=REINVENT,
        track_hash=track.content_hash,
    )  # fmt: skip
    assert result.physics == PHYSICAL
    record_race(league, result)
    # A lap that counts under a real car's floor is refused, as any other lap is.
    laps = (replace(result.laps[0], time_seconds=2.0, raw_seconds=2.0), *result.laps[1:])
    forged = replace(result, result_id=new_id(), laps=laps)
    with pytest.raises(LeagueError, match=r"lap 1 of 2\.000 s is faster than a real car can"):
        record_race(league, forged)


def test_a_night_heat_under_the_floor_is_not_recorded(league: League, floor: float) -> None:
    from league.nights import add_entrant, draw_heats, new_night

    track = resolve_track(REINVENT)
    night = new_night(league, track, name="friday")
    add_entrant(league, night, "ana", "reference")
    (heat,) = draw_heats(league, night, seed=1)
    forged = race_result("ana", [4.1], track=track, rules=night.rules)
    with pytest.raises(LeagueError, match=f"no lap under {floor:.3f} s is possible there"):
        record_race(league, forged, night.id, heat_id=heat.id)
    assert league.query_one("SELECT count(*) FROM races WHERE night_id = ?", (night.id,))[0] == 0


def test_tracks_show_says_the_floor(capsys: pytest.CaptureFixture[str]) -> None:
    floor = fastest_possible_lap(resolve_track("hairpin-circuit"))
    assert main(["tracks", "show", "hairpin-circuit"]) == 0
    out = capsys.readouterr().out
    assert out.endswith(f"\nNo lap under {floor:.3f} s is accepted (DeepRacer's rules at 4 m/s).\n")
    assert main(["tracks", "show", "hairpin-circuit", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["lap_floor_s"] == round(floor, 3)

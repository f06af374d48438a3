"""Where a lap loses time: sectors, sector times against the limit lap, and `racer-tui
coach` on a model's evaluation."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from racer_tui.cli.main import main
from sim.coach.lap_analysis import analyse_lap, coach_sentence, path_of_race_lap
from sim.coach.limit_lap import limit_lap
from sim.coach.sectors import track_sectors
from sim.garage.folder import open_model
from sim.garage.options import new_model
from sim.race.driver import ReferenceRaceDriver
from sim.race.engine import run_race
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.evaluation import evaluate_model


def test_a_track_is_split_into_corners_and_straights_from_the_line() -> None:
    track = resolve_track("reinvent_base")
    lap = limit_lap(track)
    sectors = track_sectors(track, lap)
    assert sectors[0].start == 0.0 and sectors[-1].end == pytest.approx(track.length)
    assert all(a.end == b.start for a, b in itertools.pairwise(sectors))
    assert all(a.corner != b.corner for a, b in itertools.pairwise(sectors))
    corners = [s.name for s in sectors if s.corner]
    assert corners == [f"T{n}" for n in range(1, len(corners) + 1)] and len(corners) >= 3
    assert all(s.length >= 0.75 for s in sectors)


def test_a_race_lap_is_explained_sector_by_sector() -> None:
    track = resolve_track("reinvent_base")
    race = run_race(track, RaceRules(window_seconds=20.0))
    lap = limit_lap(track)
    sectors = track_sectors(track, lap)
    second = race.laps[1]
    report = analyse_lap(track, lap, sectors, path_of_race_lap(race.trace, 2, second.raw_seconds))
    assert report.seconds == second.raw_seconds and report.limit_seconds == lap.flying_seconds
    assert report.gap_percent > 0.0  # the reference driver is slower than the limit
    driven = sum(item.seconds for item in report.sectors)
    assert driven == pytest.approx(report.seconds, rel=0.03)
    assert sum(item.limit_seconds for item in report.sectors) == pytest.approx(
        lap.flying_seconds, rel=0.01
    )
    worst = report.ranked()[0]
    assert worst.lost == max(item.lost for item in report.sectors) > 0.05
    assert coach_sentence(worst).startswith(f"{worst.sector.name}: ")
    assert f"{worst.lost:.2f} s lost" in coach_sentence(worst)
    first = analyse_lap(track, lap, sectors, path_of_race_lap(race.trace, 1))
    assert first.limit_seconds == lap.standing_seconds  # a lap from rest: the standing limit


def test_coach_explains_a_models_evaluated_lap(capsys: pytest.CaptureFixture[str]) -> None:
    new_model("coachee", track="hairpin-circuit")
    folder = open_model("coachee")
    code = main(["coach", "coachee"])
    assert code == 2 and "has not been trained, so it has no lap" in capsys.readouterr().err
    track = folder.track()
    evaluate_model(folder, trials=2, driver=ReferenceRaceDriver(track))
    assert main(["coach", "coachee", "--json"]) == 0
    coached = json.loads(capsys.readouterr().out)
    assert coached["track"] == "hairpin-circuit" and coached["lap"] in ("trial 1", "trial 2")
    lost = [item["lost_s"] for item in coached["sectors"]]
    assert lost == sorted(lost, reverse=True)  # ranked by time lost
    gap = (coached["lap_s"] / coached["flying_limit_s"] - 1.0) * 100.0
    assert coached["gap_to_flying_limit_percent"] == pytest.approx(gap, abs=0.1)
    assert coached["flying_limit_s"] >= coached["car_flying_limit_s"]  # its actions cost
    assert all(item["sentence"].startswith(item["sector"]) for item in coached["sectors"])
    assert main(["coach", "coachee", "--lap", "2"]) == 0
    assert "trial 2" in capsys.readouterr().out
    assert main(["coach", "coachee", "--lap", "7"]) == 2
    assert "from 1 to 2" in capsys.readouterr().err
    assert np.isfinite(coached["lap_s"])


def test_a_sector_faster_than_the_limit_lap_says_so() -> None:
    from sim.coach.lap_analysis import SectorReport
    from sim.coach.sectors import Sector

    corner = Sector("T2", corner=True, start=3.0, end=5.0)
    faster = SectorReport(corner, 0.9, 1.0, off_line=0.2, speed_gap=0.1, apex_gap=0.0,
                          braking_gap=0.0)  # fmt: skip
    # The limit lap keeps all four wheels on the road; a car may cut further inside.
    assert coach_sentence(faster) == (
        "T2: 0.10 s faster than the limit lap, 0.20 m off its line "
        "(which keeps all four wheels on the road)."
    )
    assert SectorReport(corner, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0).lost_text == "+0.00 s"
    assert SectorReport(corner, 0.999, 1.0, 0.0, 0.0, 0.0, 0.0).lost_text == "+0.00 s"
    level = SectorReport(corner, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0)
    assert coach_sentence(level) == "T2: no time lost against the limit lap."

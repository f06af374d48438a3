"""DeepRacer on AWS's timing methods: racer-tui's ranking under matching rules gives DRoA's
scores and order, and `leaderboard --format droa` writes DRoA's rankings."""

from __future__ import annotations

import json
import random
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from league import nights
from league.droa_rankings import (
    INVALID_MS,
    DroaLap,
    TimingMethod,
    droa_rules_for,
    droa_stats,
    ranking_score,
)
from league.races import record_race
from league.store import League
from racer_tui.cli.main import main
from sim.race.rules import DROA_RULES, RaceRules, RankingMethod, preset_rules, score_laps
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, race_result


@dataclass(frozen=True)
class Lap:
    time_seconds: float
    offtracks: int
    valid: bool


RANKING_OF = {
    TimingMethod.AVG_LAP_TIME: RankingMethod.BEST_AVERAGE,
    TimingMethod.BEST_LAP_TIME: RankingMethod.BEST_LAP,
    TimingMethod.TOTAL_TIME: RankingMethod.TOTAL_TIME,
}


def rules_like_droa(timing: TimingMethod, minimum: int, laps: int) -> RaceRules:
    ranking = RANKING_OF[timing]
    return replace(
        DROA_RULES,
        ranking=ranking,
        ranking_laps=laps if timing is TimingMethod.TOTAL_TIME else max(minimum, 1),
        lap_count=laps,
        min_laps=minimum,
    )


@pytest.mark.parametrize("timing", list(TimingMethod))
@pytest.mark.parametrize("minimum", [1, 2, 3])
def test_racer_tui_scores_laps_as_droa_does(timing: TimingMethod, minimum: int) -> None:
    rng = random.Random(f"{timing}-{minimum}")
    for _ in range(300):
        # As DRoA's simulator writes them (unlimited resets, laps run on): every record a
        # completed lap, or a single unfinished one when no lap was completed.
        if rng.random() < 0.1:
            droa_laps = [DroaLap(rng.randint(1000, 16000), False, 3, 0, 3)]
        else:
            droa_laps = []
            for _ in range(rng.randint(max(1, minimum - 1), 6)):
                offtracks = rng.choice([0, 0, 0, 1, 2, 5])
                droa_laps.append(DroaLap(rng.randint(9000, 16000), True, offtracks, 0, offtracks))
        count = len(droa_laps)
        stats = droa_stats(droa_laps, minimum)
        expected = ranking_score(stats, timing, minimum)
        rules = rules_like_droa(timing, min(minimum, count), count)
        if minimum > count:  # a race shorter than DRoA's minimum: never ranked
            assert expected is None
            continue
        ours = score_laps(
            [Lap(lap.elapsed_ms / 1000, lap.offtracks, lap.completed) for lap in droa_laps],
            rules,
        )
        if expected is None:
            assert ours.value is None, (droa_laps, ours)
            continue
        assert ours.value is not None, (droa_laps, stats)
        assert int(ours.value * 1000 + 1e-6) == expected, (droa_laps, ours, stats)
        assert droa_rules_for(rules) == (timing, minimum)


def test_droa_s_stats_for_its_own_example() -> None:
    laps = [
        DroaLap(12500, True, 1, 0, 1),
        DroaLap(11800, True, 0, 0, 0),
        DroaLap(12735, True, 0, 0, 0),
    ]
    stats = droa_stats(laps, 3)
    assert stats == {
        "avgLapTime": 12345,
        "avgResets": 1 / 3,
        "bestLapTime": 11800,
        "collisionCount": 0,
        "completedLapCount": 3,
        "offTrackCount": 1,
        "resetCount": 1,
        "totalLapTime": 37035,
        "bestLapOffTrackCount": 0,
        "avgLapOffTrackCount": 1,
    }
    assert droa_stats([], 3)["bestLapTime"] == INVALID_MS
    assert ranking_score(droa_stats(laps[:2], 3), TimingMethod.BEST_LAP_TIME, 3) is None


def test_the_droa_preset_is_droa_s_proposed_race() -> None:
    rules = preset_rules("droa")
    assert rules is DROA_RULES
    assert (rules.ranking, rules.ranking_laps, rules.lap_count) == (RankingMethod.TOTAL_TIME, 3, 3)
    assert rules.max_offtracks_per_lap is None
    assert (rules.penalty_seconds, rules.collision_penalty_seconds) == (1.0, 1.0)


def test_a_night_under_the_droa_preset_ranks_as_droa_would(
    league: League, league_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    night = nights.new_night(league, resolve_track(TRACK), rules=DROA_RULES)
    laps = {
        "ana": ([10.0, 10.5, 11.0], [0, 1, 0]),
        "bob": ([9.5, 12.0, 10.0], [2, 0, 0]),
        "cy": ([10.2, 10.3, 10.9], [0, 0, 0]),
    }
    for racer, (times, offtracks) in laps.items():
        result = race_result(racer, times, offtracks=offtracks, rules=DROA_RULES, model=racer)
        record_race(league, result, night.id)
    league.conn.commit()
    assert (
        main(["leaderboard", "--db", str(league_path), "--night", night.id, "--format", "json"])
        == 0
    )
    ours = json.loads(capsys.readouterr().out)
    assert (
        main(["leaderboard", "--db", str(league_path), "--night", night.id, "--format", "droa"])
        == 0
    )
    document = json.loads(capsys.readouterr().out)
    [board] = document["leaderboards"]
    assert (board["timingMethod"], board["minimumLaps"]) == ("TOTAL_TIME", 3)
    droa_order = [(r["userProfile"]["alias"], r["rankingScore"]) for r in board["rankings"]]
    our_rows = ours["rows"] if isinstance(ours, dict) else ours
    our_order = [(row["racer"], round(row["score"] * 1000)) for row in our_rows]
    assert droa_order == our_order
    # 1 s per off-track inside each lap's time, as DRoA's simulator adds it.
    assert droa_order[0] == ("cy", 31400)
    assert board["rankings"][1]["stats"]["offTrackCount"] in (1, 2)


def test_a_night_under_droa_s_reward_rules_takes_only_what_droa_takes(league: League) -> None:
    from league.errors import LeagueError
    from sim.garage.options import new_model
    from sim.race.rules import rules_from_mapping

    rules = rules_from_mapping({"reward_rules": "droa"}, base=DROA_RULES)
    assert "reward functions DeepRacer on AWS would take" in rules.describe()
    night = nights.new_night(league, resolve_track(TRACK), rules=rules)
    from sim.training.policy import build_network, save_policy

    fine = new_model("fine")  # the default template passes DRoA's validator
    whole = new_model("whole")
    for trained in (fine, whole):  # a night enters only a model that can drive
        save_policy(trained.policy_file, build_network(trained.metadata()))
    nights.add_entrant(league, night, "ana", fine.name)
    nights.add_entrant(league, night, "bob", "reference")
    whole.reward_file.write_text("def reward_function(params):\n    return 1\n")
    with pytest.raises(LeagueError, match=r"refused by DeepRacer on AWS.*non-floating"):
        nights.add_entrant(league, night, "cy", whole.name)
    assert [entrant.racer for entrant in nights.entrants(league, night)] == ["ana", "bob"]

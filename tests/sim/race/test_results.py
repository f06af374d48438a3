"""Scoring under each ranking method, the league's total order over race results, and
results as JSON that crosses machines."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import pytest

from league.ranking import rank
from sim.foundation.ids import new_id
from sim.race.engine import run_race
from sim.race.result import LapRecord, RaceResult, ResultError, now_iso
from sim.race.rules import (
    RaceRules,
    RankingMethod,
    RulesError,
    load_rules,
    rules_from_mapping,
    score_laps,
)
from sim.tracks.catalog import resolve_track


def laps_of(times: Sequence[float], offtracks: Sequence[int] = (), penalty: float = 3.0):
    """LapRecords with these times (penalties included) and off-tracks (default none)."""
    counts = list(offtracks) + [0] * (len(times) - len(offtracks))
    records, clock = [], 0.0
    for number, (time, count) in enumerate(zip(times, counts, strict=True), start=1):
        records.append(
            LapRecord(
                number=number,
                time_seconds=time,
                raw_seconds=time - count * penalty,
                penalty_seconds=count * penalty,
                offtracks=count,
                valid=count <= 3,
                started_at=clock,
            )
        )
        clock += time
    return tuple(records)


def result_of(
    racer: str,
    times: Sequence[float],
    offtracks: Sequence[int] = (),
    *,
    rules: RaceRules | None = None,
    started_at: str = "2025-03-01T19:00:00.000Z",
) -> RaceResult:
    rules = rules or RaceRules()
    laps = laps_of(times, offtracks)
    return RaceResult(
        result_id=new_id(),
        racer=racer,
        model_name=f"{racer}-car",
        model_hash="sha256:" + "0" * 64,
        track_name="hairpin-circuit",
        track_hash="1" * 64,
        rules=rules,
        seed=0,
        laps=laps,
        scoring=score_laps(laps, rules),
        total_offtracks=sum(lap.offtracks for lap in laps),
        started_at=started_at,
    )


# --- ranking methods ------------------------------------------------------------------------


def test_best_lap_is_the_fastest_valid_lap() -> None:
    laps = laps_of([10.0, 8.0, 9.0, 7.5], offtracks=[0, 1, 0, 4])
    score = score_laps(laps, RaceRules())
    assert (score.value, score.lap_numbers, score.offtracks, score.valid_laps) == (8.0, (2,), 1, 3)


def test_best_average_takes_consecutive_valid_laps() -> None:
    rules = RaceRules(ranking=RankingMethod.BEST_AVERAGE, ranking_laps=3)
    # Laps 2-4 would average 8.0, but lap 3 has 4 off-tracks; laps 4-6 average 9.0.
    laps = laps_of([12.0, 8.0, 8.0, 9.0, 9.0, 9.0], offtracks=[0, 0, 4, 0, 0, 0])
    score = score_laps(laps, rules)
    assert score.value == pytest.approx(9.0)
    assert score.lap_numbers == (4, 5, 6)
    too_few = score_laps(laps_of([8.0, 8.0]), rules)
    assert too_few.value is None and too_few.valid_laps == 2


def test_total_time_adds_the_first_n_valid_laps() -> None:
    rules = RaceRules(ranking=RankingMethod.TOTAL_TIME, ranking_laps=3)
    laps = laps_of([10.0, 7.0, 9.0, 8.0, 6.0], offtracks=[0, 4, 1, 0, 0])
    score = score_laps(laps, rules)
    assert score.value == pytest.approx(27.0)  # laps 1, 3, 4
    assert score.lap_numbers == (1, 3, 4)
    assert score.offtracks == 1


def test_no_valid_lap_means_no_score_and_last_place() -> None:
    nothing = result_of("Zed", [9.0], offtracks=[5])
    assert nothing.score is None and nothing.best_lap is None
    slow = result_of("Amy", [30.0])
    assert rank([nothing, slow]) == [slow, nothing]


# --- the total order -------------------------------------------------------------------------


def test_rank_orders_by_score_first() -> None:
    fast, slow = result_of("Bo", [8.0]), result_of("Al", [8.5])
    assert rank([slow, fast]) == [fast, slow]


def test_equal_scores_rank_fewer_offtracks_in_the_scoring_lap_first() -> None:
    clean = result_of("Bo", [9.0])
    messy = result_of("Al", [9.0], offtracks=[1])
    assert rank([messy, clean]) == [clean, messy]


def test_then_more_valid_laps() -> None:
    more = result_of("Bo", [9.0, 9.5, 9.6])
    fewer = result_of("Al", [9.0, 9.5])
    assert rank([fewer, more]) == [more, fewer]


def test_then_the_earlier_result() -> None:
    earlier = result_of("Bo", [9.0], started_at="2025-03-01T19:00:00.000Z")
    later = result_of("Al", [9.0], started_at="2025-03-01T19:04:00.000Z")
    assert rank([later, earlier]) == [earlier, later]


def test_then_the_racers_name() -> None:
    al, bo = result_of("al", [9.0]), result_of("Bo", [9.0])
    assert rank([bo, al]) == [al, bo]
    assert rank([al, bo]) == [al, bo]


def test_scores_equal_to_the_millisecond_tie() -> None:
    a = result_of("Bo", [9.0001])
    b = result_of("Al", [9.0004], offtracks=[0])
    assert rank([a, b]) == [b, a]  # same 9.000 score and off-tracks: name decides


# --- JSON -------------------------------------------------------------------------------------


def test_json_round_trip_keeps_everything_but_the_trace() -> None:
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RaceRules(window_seconds=20.0), racer="Ada Lovelace")
    data = json.loads(json.dumps(result.to_json()))
    assert "trace" not in data
    back = RaceResult.from_json(data)
    assert back.trace is None
    assert back.laps == result.laps
    assert back.scoring == result.scoring
    assert back.rules == result.rules
    for field in ("result_id", "racer", "model_name", "model_hash", "track_hash", "started_at"):
        assert getattr(back, field) == getattr(result, field)
    assert data["best_lap_seconds"] == result.best_lap.time_seconds  # type: ignore[union-attr]


def valid_json() -> dict[str, object]:
    return result_of("Ada", [9.0, 8.5], offtracks=[1, 0]).to_json()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"result_id": "../../etc"}, "result_id"),
        ({"racer": ""}, "racer"),
        ({"racer": "a\x1b[31mred"}, "racer"),
        ({"model_hash": "no spaces allowed"}, "model_hash"),
        ({"started_at": "yesterday"}, "started_at"),
        ({"started_at": "2025-03-01T19:00:00"}, "started_at"),
        ({"seed": -1}, "seed"),
        ({"rules": {"window_seconds": "long"}}, "window_seconds"),
        ({"laps": "many"}, "laps"),
        ({"total_offtracks": 0}, "total_offtracks"),
        ({"scoring": {"value": 1.0}}, "scoring"),
        ({"format": 99}, "format"),
    ],
)
def test_bad_json_is_rejected_naming_the_field(change: dict[str, object], message: str) -> None:
    data = {**valid_json(), **change}
    with pytest.raises(ResultError, match=message):
        RaceResult.from_json(data)


def test_tampered_laps_are_rejected() -> None:
    data = valid_json()
    laps = data["laps"]
    assert isinstance(laps, list)
    laps[0] = {**laps[0], "time_seconds": 1.0}
    with pytest.raises(ResultError, match=r"laps\[0\]"):
        RaceResult.from_json(data)
    data = valid_json()
    laps = data["laps"]
    assert isinstance(laps, list)
    laps[0] = {**laps[0], "offtracks": 9, "valid": True}
    with pytest.raises(ResultError, match="off-tracks"):
        RaceResult.from_json({**data, "total_offtracks": 9})


def test_now_iso_sorts_as_text() -> None:
    first, second = now_iso(), now_iso()
    assert len(first) == len(second) == 24 and first <= second


# --- rules files ------------------------------------------------------------------------------


def test_rules_load_from_yaml_with_defaults_for_unset_keys(tmp_path: Path) -> None:
    path = tmp_path / "rules.yaml"
    path.write_text(
        "window_seconds: 180\nmax_offtracks_per_lap: unlimited\nranking: best_average\n"
        "ranking_laps: 2\n"
    )
    rules = load_rules(path)
    assert rules == RaceRules(
        window_seconds=180.0,
        max_offtracks_per_lap=None,
        ranking=RankingMethod.BEST_AVERAGE,
        ranking_laps=2,
    )
    assert rules_from_mapping(rules.to_dict()) == rules


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("window_secs: 240\n", "window_secs"),
        ("window_seconds: forever\n", "window_seconds"),
        ("window_seconds: 5\n", "window_seconds"),
        ("penalty_seconds: -1\n", "penalty_seconds"),
        ("max_offtracks_per_lap: lots\n", "max_offtracks_per_lap"),
        ("ranking: fastest\n", "ranking"),
        ("ranking_laps: 0\n", "ranking_laps"),
        ("ranking_laps: true\n", "ranking_laps"),
        ("lap_count: 0\n", "lap_count"),
        ("lap_count: 2.5\n", "lap_count"),
        ("lap_count: many\n", "lap_count"),
        ("lap_count: 2\nranking: total_time\n", "ranking_laps at most 2"),
    ],
)
def test_a_bad_rules_file_names_the_key(tmp_path: Path, text: str, key: str) -> None:
    path = tmp_path / "rules.yaml"
    path.write_text(text)
    with pytest.raises(RulesError, match=key) as caught:
        load_rules(path)
    assert str(path) in str(caught.value)
    assert "\n" not in str(caught.value)


def test_a_rules_file_that_is_not_yaml_or_not_a_mapping(tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("window_seconds: [240\n")
    with pytest.raises(RulesError, match="not valid YAML"):
        load_rules(broken)
    listed = tmp_path / "list.yaml"
    listed.write_text("- 240\n")
    with pytest.raises(RulesError, match="mapping"):
        load_rules(listed)
    with pytest.raises(RulesError, match="cannot read"):
        load_rules(tmp_path / "missing.yaml")


def test_a_rules_file_of_random_bytes_or_with_a_key_twice_is_refused(tmp_path: Path) -> None:
    noise = tmp_path / "noise.yaml"
    noise.write_bytes(bytes(range(128, 256)) * 4)
    with pytest.raises(RulesError, match="is not UTF-8 text; give a YAML file saved as UTF-8"):
        load_rules(noise)
    twice = tmp_path / "twice.yaml"
    twice.write_text("penalty_seconds: 2\nwindow_seconds: 240\npenalty_seconds: 0\n")
    with pytest.raises(RulesError, match=r"'penalty_seconds' is given twice \(line 3\)"):
        load_rules(twice)


def test_no_lap_can_beat_the_shortest_loop_at_top_speed() -> None:
    from sim.coach.plausible import fastest_possible_lap, hull_floor, shortest_loop_metres
    from sim.physics.reference_driver import reference_lap
    from sim.tracks.catalog import resolve_track

    for name in ("reinvent_base", "hairpin-circuit", "beginner-oval"):
        track = resolve_track(name)
        assert shortest_loop_metres(track) < track.length  # the inside of the road
        assert hull_floor(track) == pytest.approx(shortest_loop_metres(track) / 4.0)
        assert reference_lap(track).lap_time > fastest_possible_lap(track)  # never refused


def test_a_rules_file_may_merge_an_anchor(tmp_path: Path) -> None:
    merged = tmp_path / "merged.yaml"
    merged.write_text("base: &base\n  penalty_seconds: 3\nrules:\n  <<: *base\n")
    from sim.foundation.strict_yaml import load_data

    assert load_data(merged.read_text())["rules"] == {"penalty_seconds": 3}


def test_a_lap_count_race_is_rules_of_its_own_and_a_time_race_keeps_its_stored_form(
    tmp_path: Path,
) -> None:
    path = tmp_path / "rules.yaml"
    path.write_text("lap_count: 5\nranking: total_time\n")
    rules = load_rules(path)
    assert rules.lap_count == 5
    assert rules_from_mapping(rules.to_dict()) == rules
    assert rules.describe().startswith("race of 5 laps within 4:00")
    assert rules.lap_of(2) == "Lap 2 of 5"
    assert rules.lap_of(6) == "Lap 5 of 5"  # the count moves on as the last lap ends
    # A time race's rules are stored as they were before lap-count races existed, so every
    # result and night recorded until now keeps its content hash.
    assert "lap_count" not in RaceRules().to_dict()
    assert rules_from_mapping({"lap_count": None}, base=rules) == RaceRules(
        ranking=RankingMethod.TOTAL_TIME
    )
    assert RaceRules().lap_of(2) == "Lap 2"


def test_a_result_with_more_laps_than_its_lap_count_race_is_refused() -> None:
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RaceRules(window_seconds=20.0))
    assert result.completed_laps >= 2
    data = result.to_json()
    data["rules"] = {**data["rules"], "lap_count": 1}  # type: ignore[dict-item]
    with pytest.raises(ResultError, match="race of 1 laps cannot have 2 counting laps"):
        RaceResult.from_json(data)

"""A league night from opening to season points: frozen rules, entrants, a drawn order,
headless heats, standings and points, closing, and the season table."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import pytest

from league import nights
from league.errors import LeagueError
from league.races import record_race
from league.records import record_body
from league.seasons import get_season, new_season, parse_points, season_standings
from league.store import League
from sim.race.driver import reference_driver
from sim.race.result import RaceResult
from sim.race.rules import RaceRules, RankingMethod
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track
from tests.league.helpers import TRACK, model_folder, race_result

LAPS = {  # racer -> lap times of their heat
    "ana": [11.0, 10.6, 10.9],
    "bob": [10.8, 10.7],
    "cy": [12.0, 12.0, 12.0],
    "dee": [],  # never completes a lap
}


class FakeEngine:
    """Stands in for sim.race.engine.run_race: the laps above, and what it was asked."""

    def __init__(self, laps: dict[str, list[float]]) -> None:
        self.laps = laps
        self.calls: list[dict[str, Any]] = []

    def __call__(
        self, track: Track, rules: RaceRules, driver: Any, *, racer: str, seed: int
    ) -> RaceResult:
        self.calls.append({"racer": racer, "model": driver, "rules": rules, "seed": seed})
        return race_result(racer, self.laps[racer], track=track, rules=rules, model=driver)


def _resolve(spec: str, track: Track) -> Any:
    return spec  # the fake engine takes the model spec as its "driver"


def _night_with_entrants(league: League, rules: RaceRules, season: str | None = None) -> Any:
    night = nights.new_night(
        league, resolve_track(TRACK), rules=rules, name="Friday", season=season
    )
    for racer in LAPS:
        nights.add_entrant(league, night, racer, "reference")
    return night


def test_a_full_night_gives_standings_and_points(league: League) -> None:
    new_season(league, "spring", parse_points("10,6,4"))
    rules = RaceRules(window_seconds=60.0, ranking=RankingMethod.BEST_LAP)
    night = _night_with_entrants(league, rules, season="spring")
    order = nights.draw_heats(league, night, seed=7)
    expected = list(nights.entrants(league, night))
    random.Random(7).shuffle(expected)
    assert [heat.entrant.racer for heat in order] == [entrant.racer for entrant in expected]

    engine = FakeEngine(LAPS)
    recorded = nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=engine)
    assert len(recorded) == 4
    assert [call["racer"] for call in engine.calls] == [e.racer for e in expected]
    assert all(call["rules"] == rules for call in engine.calls)
    assert len({call["seed"] for call in engine.calls}) == 4
    assert nights.pending_heats(league, night) == []

    standings = nights.close_night(league, night, "host")
    assert [(s.position, s.entry.racer, s.points) for s in standings] == [
        (1, "ana", 10),
        (2, "bob", 6),
        (3, "cy", 4),
        (None, "dee", 0),
    ]
    closed = nights.get_night(league, night.id)
    assert closed.closed
    with pytest.raises(LeagueError, match="closed"):
        nights.add_entrant(league, closed, "eve", "reference")
    with pytest.raises(LeagueError, match="closed"):
        record_race(league, race_result("eve", [9.0], rules=rules), night.id)


def test_rules_are_frozen_and_a_race_under_other_rules_is_refused(league: League) -> None:
    rules = RaceRules(window_seconds=120.0, penalty_seconds=5.0)
    night = nights.new_night(league, resolve_track(TRACK), rules=rules)
    assert nights.get_night(league, night.id).rules == rules
    with pytest.raises(LeagueError, match="frozen rules"):
        record_race(league, race_result("ana", [10.0]), night.id)
    other_track = race_result("ana", [10.0], rules=rules, track=resolve_track("speedway"))
    with pytest.raises(LeagueError, match="track"):
        record_race(league, other_track, night.id)


def test_ranking_by_the_nights_method(league: League) -> None:
    rules = RaceRules(ranking=RankingMethod.TOTAL_TIME, ranking_laps=3)
    night = _night_with_entrants(league, rules)
    nights.draw_heats(league, night, seed=1)
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS))
    standings = nights.standings(league, night)
    # Only ana and cy drove three laps: bob's two fast laps do not make a total.
    assert [(s.position, s.entry.racer, s.entry.score) for s in standings] == [
        (1, "ana", pytest.approx(32.5)),
        (2, "cy", pytest.approx(36.0)),
        (None, "bob", None),
        (None, "dee", None),
    ]


def test_closing_with_heats_waiting_needs_force(league: League) -> None:
    night = _night_with_entrants(league, RaceRules())
    nights.draw_heats(league, night, seed=2)
    with pytest.raises(LeagueError, match="4 heat"):
        nights.close_night(league, night, "host")
    assert nights.close_night(league, night, "host", force=True) == []


def test_a_redraw_orders_only_who_has_not_raced(league: League) -> None:
    night = _night_with_entrants(league, RaceRules())
    nights.draw_heats(league, night, seed=3)
    nights.run_heats(
        league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS), limit=1
    )
    heats = nights.draw_heats(league, night, seed=4)
    raced = [heat for heat in heats if heat.race_id is not None]
    waiting = [heat for heat in heats if heat.race_id is None]
    assert len(raced) == 1 and len(waiting) == 3
    assert raced[0].entrant.racer not in {heat.entrant.racer for heat in waiting}


def test_a_night_needs_entrants_to_draw(league: League) -> None:
    night = nights.new_night(league, resolve_track(TRACK))
    with pytest.raises(LeagueError, match="no entrants"):
        nights.draw_heats(league, night)
    with pytest.raises(LeagueError, match="no drawn heats"):
        nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine({}))


def test_heats_run_on_the_real_engine(league: League) -> None:
    rules = RaceRules(window_seconds=15.0)
    night = nights.new_night(league, resolve_track(TRACK), rules=rules)
    nights.add_entrant(league, night, "ana", "reference")
    nights.add_entrant(league, night, "bob", "reference")
    nights.draw_heats(league, night, seed=1)
    track = nights.find_night_track(night)
    nights.run_heats(league, night, track, lambda spec, t: reference_driver(t))
    standings = nights.standings(league, night)
    assert {s.entry.racer for s in standings} == {"ana", "bob"}
    assert all(s.entry.best_lap is not None for s in standings)
    # Same car, same physics: identical laps, so the earlier race wins the tie.
    assert standings[0].entry.best_lap == standings[1].entry.best_lap
    assert standings[0].entry.recorded_at <= standings[1].entry.recorded_at


def test_season_standings_add_up_points_with_countback(league: League) -> None:
    season = new_season(league, "summer", parse_points("5,3,1"))
    first = _night_with_entrants(league, RaceRules(), season="summer")
    nights.draw_heats(league, first, seed=1)
    nights.run_heats(league, first, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS))
    nights.close_night(league, first, "host")
    swapped = {**LAPS, "ana": [11.5], "bob": [10.0]}
    second = nights.new_night(league, resolve_track(TRACK), season="summer", name="Sat")
    for racer in swapped:
        nights.add_entrant(league, second, racer, "reference")
    nights.draw_heats(league, second, seed=2)
    nights.run_heats(league, second, resolve_track(TRACK), _resolve, run_race=FakeEngine(swapped))
    open_night_points = season_standings(league, get_season(league, "summer"))
    assert [(s.racer, s.points) for s in open_night_points][:2] == [("ana", 5), ("bob", 3)]
    nights.close_night(league, second, "host")
    table = season_standings(league, season)
    # ana 5+3 = bob 3+5 = 8: one win each, one second each; the name decides, as documented.
    assert [(s.position, s.racer, s.points, s.wins, s.nights) for s in table] == [
        (1, "ana", 8, 1, 2),
        (2, "bob", 8, 1, 2),
        (3, "cy", 2, 0, 2),
        (4, "dee", 0, 0, 2),
    ]


def test_points_tables_are_validated() -> None:
    assert parse_points("25, 18, 15") == (25, 18, 15)
    for bad in ("", "a,b", "10,20", "-1"):
        with pytest.raises(LeagueError):
            parse_points(bad)


def test_an_entrant_model_is_checked_when_added(league: League, tmp_path: Path) -> None:
    night = nights.new_night(league, resolve_track(TRACK))
    with pytest.raises(LeagueError, match="no model named 'ghost'"):
        nights.add_entrant(league, night, "ana", "ghost")
    with pytest.raises(LeagueError, match="no bundle file"):
        nights.add_entrant(league, night, "ana", "missing.racer-bundle")
    folder = model_folder(tmp_path, "by-path")
    # The host walk: an untrained model was entered, and failed only at its heat.
    with pytest.raises(LeagueError, match="'by-path' has no trained policy yet; train it"):
        nights.add_entrant(league, night, "ana", str(folder))
    from sim.garage.folder import ModelFolder
    from sim.training.policy import build_network, save_policy

    trained = ModelFolder(folder)
    save_policy(trained.policy_file, build_network(trained.metadata()))
    entrant = nights.add_entrant(league, night, "ana", str(folder))
    assert entrant.model == str(folder.resolve())
    with pytest.raises(LeagueError, match="already entered"):
        nights.add_entrant(league, night, "ANA", str(folder))


def test_a_night_of_simulated_and_physical_cars_is_one_ranking(league: League) -> None:
    """The host may mix cars: the night's standings rank them all once, as the season
    counts them; only the leaderboard keeps a real track's laps on a board of their own."""
    from dataclasses import replace

    from league.leaderboard import Filters, leaderboard
    from league.night_report import standing_car
    from sim.physics.labels import PHYSICAL

    new_season(league, "mixed", parse_points("10,6,4"))
    rules = RaceRules(window_seconds=60.0)
    night = nights.new_night(league, resolve_track(TRACK), rules=rules, season="mixed")
    nights.add_entrant(league, night, "ana", "reference")
    nights.add_entrant(league, night, "bob", "physical:blue car")
    nights.add_entrant(league, night, "cy", "reference")
    order = nights.draw_heats(league, night, seed=5)
    laps = {"ana": [11.0], "bob": [10.5], "cy": [12.0]}
    for heat in order:
        result = race_result(heat.entrant.racer, laps[heat.entrant.racer], rules=rules)
        if heat.entrant.racer == "bob":
            result = replace(result, physics=PHYSICAL)
        record_race(league, result, night.id, heat_id=heat.id)
    standings = nights.close_night(league, night, "host")
    assert [(s.position, s.entry.racer, s.points) for s in standings] == [
        (1, "bob", 10),
        (2, "ana", 6),
        (3, "cy", 4),
    ]
    # Named as the night's entrants are: a physical car's name never reads as a model's.
    # (`race_result` names every result's model "car".)
    assert [standing_car(s) for s in standings] == ["car (physical)", "car", "car"]
    season = season_standings(league, get_season(league, "mixed"))
    assert [(s.racer, s.points) for s in season] == [("bob", 10), ("ana", 6), ("cy", 4)]
    boards = leaderboard(league, Filters(), method=None)
    assert [(row.racer, row.rank, row.physics == PHYSICAL) for row in boards] == [
        ("ana", 1, False),
        ("cy", 2, False),
        ("bob", 1, True),
    ]


def test_an_entrant_withdrawn_before_their_heat_leaves_the_order(league: League) -> None:
    night = _night_with_entrants(league, RaceRules())
    by_racer = {entrant.racer: entrant for entrant in nights.entrants(league, night)}
    nights.withdraw_entrant(league, night, by_racer["dee"].id, "host")
    assert [entrant.racer for entrant in nights.entrants(league, night)] == ["ana", "bob", "cy"]
    nights.add_entrant(league, night, "dee", "reference")  # entered again: not a duplicate
    nights.draw_heats(league, night, seed=3)
    nights.run_heats(
        league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS), limit=1
    )
    first = nights.heats(league, night)[0]
    with pytest.raises(LeagueError, match="has raced"):
        nights.withdraw_entrant(league, night, first.entrant.id, "host")
    waiting = nights.pending_heats(league, night)
    nights.withdraw_entrant(league, night, waiting[0].entrant.id, "host")  # after the draw
    assert [heat.entrant.racer for heat in nights.pending_heats(league, night)] == [
        heat.entrant.racer for heat in waiting[1:]
    ]
    with pytest.raises(LeagueError, match="no entrant"):
        nights.withdraw_entrant(league, night, waiting[0].entrant.id, "host")


def test_a_host_moves_a_waiting_heat_in_the_running_order(league: League) -> None:
    night = _night_with_entrants(league, RaceRules())
    drawn = [heat.entrant.racer for heat in nights.draw_heats(league, night, seed=5)]
    last = nights.pending_heats(league, night)[-1]
    moved = nights.move_heat(league, night, last.id, -1)
    assert [heat.entrant.racer for heat in moved] == [*drawn[:2], drawn[3], drawn[2]]
    with pytest.raises(LeagueError, match="already the first"):
        nights.move_heat(league, night, moved[0].id, -1)
    nights.run_heats(
        league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS), limit=1
    )
    raced = nights.heats(league, night)[0]
    with pytest.raises(LeagueError, match="still waiting"):
        nights.move_heat(league, night, raced.id, 1)
    waiting = nights.pending_heats(league, night)
    order = nights.move_heat(league, night, waiting[-1].id, -2)
    # Numbered in the running order; no heat races with a seed another raced with.
    assert [heat.position for heat in order] == [1, 2, 3, 4]
    assert len({heat.seed for heat in order}) == 4


def test_only_a_night_without_results_can_be_deleted(league: League) -> None:
    empty = nights.new_night(league, resolve_track(TRACK), name="mistake")
    nights.add_entrant(league, empty, "ana", "reference")
    nights.delete_night(league, empty, "host")
    assert [n.name for n in nights.list_nights(league)] == []
    with pytest.raises(LeagueError, match="no league night 'mistake'"):
        nights.get_night(league, "mistake")
    raced = _night_with_entrants(league, RaceRules())
    nights.draw_heats(league, raced, seed=1)
    nights.run_heats(
        league, raced, resolve_track(TRACK), _resolve, run_race=FakeEngine(LAPS), limit=1
    )
    with pytest.raises(LeagueError, match="cannot be deleted; close it instead"):
        nights.delete_night(league, raced, "host")
    assert [n.name for n in nights.list_nights(league)] == ["Friday"]


def test_a_night_exports_its_standings_with_points(league: League) -> None:
    import csv
    import io
    import json

    from league.night_report import night_export

    new_season(league, "export", parse_points("10,6,4"))
    night = nights.new_night(
        league, resolve_track(TRACK), rules=RaceRules(), name="Fri *night*", season="export"
    )
    nights.add_entrant(league, night, "=cmd()", "reference")  # a formula-looking name
    nights.add_entrant(league, night, "bob", "reference")
    nights.draw_heats(league, night, seed=1)
    laps = {"=cmd()": [11.0], "bob": [10.0]}
    nights.run_heats(league, night, resolve_track(TRACK), _resolve, run_race=FakeEngine(laps))
    parts = (night, nights.entrants(league, night), nights.heats(league, night))
    table = nights.standings(league, night)

    rows = list(csv.DictReader(io.StringIO(night_export(*parts, table, "csv"))))
    assert [(r["position"], r["racer"], r["best lap"], r["points"]) for r in rows] == [
        ("1", "bob", "10.000", "10"),
        ("2", "'=cmd()", "11.000", "6"),  # a spreadsheet shows it, never runs it
    ]
    markdown = night_export(*parts, table, "markdown")
    assert markdown.startswith("# Fri \\*night\\*: standings so far")
    assert "| 1 | bob | reference | 10.000 | 1 | 0 | 10 |" in markdown
    whole = json.loads(night_export(*parts, table, "json"))
    assert [s["points"] for s in whole["standings"]] == [10, 6]
    assert len(whole["heats"]) == 2 and whole["rules"]["window_seconds"] == 240.0


def test_a_night_is_held_on_a_day_of_its_own_and_older_nights_on_the_day_they_opened(
    league: League,
) -> None:
    from datetime import date, datetime

    track = resolve_track(TRACK)
    planned = nights.new_night(league, track, name="planned", held_on=date(2027, 3, 5))
    assert planned.held_on == "2027-03-05"
    before = datetime.now().date().isoformat()
    today = nights.new_night(league, track)
    after = datetime.now().date().isoformat()
    assert today.held_on in {before, after}  # the host's calendar day (even at midnight)
    assert today.name == f"{track.name} {today.held_on}"
    # A night opened before nights had a date is held on the day it was opened, and its
    # record keeps the fields (and content hash) it was shared with.
    league.conn.execute("UPDATE nights SET held_on = NULL WHERE id = ?", (planned.id,))
    older = nights.get_night(league, planned.id)
    opened = datetime.fromisoformat(older.created_at).astimezone()  # in the host's zone
    assert older.held_on == opened.date().isoformat()
    assert "held_on" not in record_body(league, "nights", planned.id)
    assert record_body(league, "nights", today.id)["held_on"] == today.held_on
    for typed in ("2026-13-01", "5 March", "20270305", "1999-12-31"):
        with pytest.raises(LeagueError, match="write it as YYYY-MM-DD"):
            nights.night_date(typed)
    assert nights.night_date(" 2027-03-05 ") == date(2027, 3, 5)
    # Slashes or dots between year, month and day read the same; the other order does not.
    assert nights.night_date("2027/03/05") == nights.night_date("2027.03.05") == date(2027, 3, 5)
    with pytest.raises(LeagueError, match="'05/03/2027' is not a night's date"):
        nights.night_date("05/03/2027")  # said back as typed


def test_an_entrants_car_is_named_the_same_everywhere(tmp_path: Path) -> None:
    """Heats, the race view, the projector and the notes name a car alike: a bundle by its
    file name, never its path; a physical car by its name, marked physical."""
    from league.nights import Entrant

    def car(model: str) -> str:
        return Entrant("id", "ada", "Ada", model).car

    assert car(str(tmp_path / "beta-car.racer-bundle")) == "beta-car.racer-bundle"
    assert car("alpha-car") == "alpha-car" and car("reference") == "reference"
    assert car("physical:red-car") == "red-car (physical)"
    assert car("physical") == "physical car"


def test_a_night_s_json_names_a_bundle_by_its_file_name_never_its_path(
    league: League, tmp_path: Path
) -> None:
    """`night show --json`, the app's export and the web's /api/night are handed to others:
    the folder a racer keeps their bundle in is theirs, not the venue's."""
    import json

    from league.night_report import night_export

    bundle = tmp_path / "ana-private-folder" / "fast.racer-bundle"
    bundle.parent.mkdir()
    bundle.write_bytes(b"")  # entering a bundle checks only that its file is there
    night = nights.new_night(league, resolve_track(TRACK), name="Friday")
    nights.add_entrant(league, night, "ana", str(bundle))
    nights.add_entrant(league, night, "bob", "reference")
    nights.draw_heats(league, night, seed=1)
    assert nights.entrants(league, night)[0].model == str(bundle)  # kept whole, here
    parts = (night, nights.entrants(league, night), nights.heats(league, night))
    text = night_export(*parts, nights.standings(league, night), "json")
    assert "ana-private-folder" not in text and str(tmp_path) not in text
    whole = json.loads(text)
    assert [e["model"] for e in whole["entrants"]] == ["fast.racer-bundle", "reference"]
    assert {h["racer"]: h["model"] for h in whole["heats"]} == {
        "ana": "fast.racer-bundle",
        "bob": "reference",
    }

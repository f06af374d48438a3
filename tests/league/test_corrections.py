"""Corrections are new rows saying who changed what and why; the originals stay, and every
leaderboard and standings table applies them."""

from __future__ import annotations

from pathlib import Path

import pytest

from league import nights
from league.assembler import assemble
from league.corrections import disqualify_lap, list_corrections, rename_racer
from league.errors import LeagueError
from league.leaderboard import Filters, leaderboard
from league.racers import add_racer, get_racer
from league.races import record_race
from league.store import League
from league.submissions import submit
from sim.race.rules import DEFAULT_RULES
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, model_folder, race_result


def test_disqualifying_a_lap_changes_the_best_lap_and_the_order(league: League) -> None:
    ana = race_result("ana", [10.0, 11.0])
    record_race(league, ana)
    record_race(league, race_result("bob", [10.5]))
    assert [row.racer for row in leaderboard(league, Filters())] == ["ana", "bob"]

    correction = disqualify_lap(league, ana.result_id, 1, reason="cut the chicane", by="steward")
    rows = leaderboard(league, Filters())
    assert [(row.racer, row.best_lap, row.valid_laps) for row in rows] == [
        ("bob", 10.5, 1),
        ("ana", 11.0, 1),
    ]
    lap = league.query_one("SELECT * FROM race_laps WHERE race_id = ? AND number = 1",
                           (ana.result_id,))  # fmt: skip
    assert lap["time_seconds"] == 10.0 and lap["valid"] == 1  # the recorded lap is untouched
    [recorded] = list_corrections(league, ana.result_id)
    assert recorded.id == correction
    assert (recorded.kind, recorded.lap_number, recorded.reason, recorded.made_by) == (
        "disqualify_lap",
        1,
        "cut the chicane",
        "steward",
    )


def test_a_submission_lap_can_be_disqualified_too(tmp_path: Path, league: League) -> None:
    stored = submit(league, assemble(str(model_folder(tmp_path, laps=(12.0, 11.0))), "ana"))
    disqualify_lap(league, stored.submission_id.lower(), 2, reason="reset", by="host")
    [row] = leaderboard(league, Filters())
    assert row.best_lap == 12.0


def test_disqualifications_reach_night_standings(league: League) -> None:
    night = nights.new_night(league, resolve_track(TRACK), rules=DEFAULT_RULES)
    ana = race_result("ana", [10.0, 13.0])
    record_race(league, ana, night.id)
    record_race(league, race_result("bob", [12.0]), night.id)
    nights.close_night(league, night, "host")
    disqualify_lap(league, ana.result_id, 1, reason="jumped the start", by="steward")
    standings = nights.standings(league, nights.get_night(league, night.id))
    assert [(s.entry.racer, s.points) for s in standings] == [("bob", 25), ("ana", 18)]


def test_bad_lap_corrections_are_refused(league: League) -> None:
    ana = race_result("ana", [10.0])
    record_race(league, ana)
    with pytest.raises(LeagueError, match="no race or submission"):
        disqualify_lap(league, "01HZZZZZZZZZZZZZZZZZZZZZZZ", 1, reason="x", by="host")
    with pytest.raises(LeagueError, match="has no lap 2"):
        disqualify_lap(league, ana.result_id, 2, reason="x", by="host")
    with pytest.raises(LeagueError, match="--reason"):
        disqualify_lap(league, ana.result_id, 1, reason="  ", by="host")
    disqualify_lap(league, ana.result_id, 1, reason="x", by="host")
    with pytest.raises(LeagueError, match="already disqualified"):
        disqualify_lap(league, ana.result_id, 1, reason="x", by="host")


def test_a_rename_changes_what_is_shown_but_not_the_racer(league: League) -> None:
    add_racer(league, "ana")
    record_race(league, race_result("ana", [10.0]))
    rename_racer(league, "ana", "Ana the Fast", by="ana", reason="new team")
    rename_racer(league, "ana", "[red]Ana[/red]", by="host")
    [row] = leaderboard(league, Filters())
    assert (row.racer, row.display_name) == ("ana", "[red]Ana[/red]")
    assert get_racer(league, "[red]Ana[/red]").name == "ana"
    assert league.query_one("SELECT display_name FROM racers")[0] == "ana"
    history = [(c.new_value, c.made_by) for c in list_corrections(league, "ana")]
    assert history == [("Ana the Fast", "ana"), ("[red]Ana[/red]", "host")]
    with pytest.raises(LeagueError, match="already shown"):
        rename_racer(league, "ana", "[red]Ana[/red]", by="host")
    with pytest.raises(LeagueError, match="no racer called"):
        rename_racer(league, "nobody", "x", by="host")

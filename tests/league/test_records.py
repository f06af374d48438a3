"""Shared rows as sync records: every row's stored hash is the hash of its rebuilt body,
and a record stored in another league ranks the same there."""

from __future__ import annotations

from pathlib import Path

import pytest

from league import nights
from league.assembler import assemble
from league.corrections import disqualify_lap, rename_racer
from league.errors import LeagueError
from league.leaderboard import Filters, leaderboard
from league.opening import open_league
from league.races import record_race
from league.records import SHARED_TABLES, record_body, records, store_record
from league.seasons import new_season
from league.store import League
from league.submissions import submit
from sim.foundation.ids import content_hash
from sim.race.rules import DEFAULT_RULES
from sim.tracks.catalog import resolve_track
from tests.league.helpers import TRACK, model_folder, race_result


def _busy_league(league: League, tmp_path: Path) -> None:
    new_season(league, "s1")
    night = nights.new_night(league, resolve_track(TRACK), season="s1")
    nights.add_entrant(league, night, "ana", "reference")
    nights.draw_heats(league, night, seed=1)
    heat = nights.pending_heats(league, night)[0]
    race = race_result("ana", [11.0, 10.5], rules=DEFAULT_RULES)
    record_race(league, race, night.id, heat_id=heat.id)
    nights.close_night(league, night, "host")
    submitted = submit(league, assemble(str(model_folder(tmp_path)), "bob"))
    disqualify_lap(league, race.result_id, 2, reason="cut", by="host")
    rename_racer(league, "bob", "Bobby", by="bob")
    assert submitted.submission_id


def test_every_shared_row_hashes_to_its_body(league: League, tmp_path: Path) -> None:
    _busy_league(league, tmp_path)
    seen = 0
    for table in SHARED_TABLES:
        for record_id, stored_hash, body in records(league, table):
            assert stored_hash == content_hash(body), (table, record_id)
            seen += 1
    assert seen >= 12


def test_records_copied_to_another_league_give_the_same_leaderboard(
    league: League, tmp_path: Path
) -> None:
    _busy_league(league, tmp_path)
    with open_league(tmp_path / "other.db") as other:
        with other.transaction():
            for table in SHARED_TABLES:
                for record_id, _, body in records(league, table):
                    assert store_record(other, table, record_id, body)
        racer_id, _, racer_body = next(records(league, "racers"))
        assert not store_record(other, "racers", racer_id, racer_body)  # pulled again: nothing

        def board(target: League) -> list[tuple[int, str, str, float | None]]:
            rows = leaderboard(target, Filters())
            return [(r.rank, r.display_name, r.record_id, r.best_lap) for r in rows]

        assert board(other) == board(league)
        first_race = next(records(league, "races"))[0]
        changed = {**record_body(league, "races", first_race), "seed": 99}
        with pytest.raises(LeagueError, match="different content"):
            store_record(other, "races", first_race, changed)

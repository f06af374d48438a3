"""Leagues on separate "machines" (separate database files) for the sync engine tests, and
what a racer would compare: the leaderboard, season and racer listings the CLI prints."""

from __future__ import annotations

import io
import json
from collections.abc import Sequence
from contextlib import redirect_stdout
from dataclasses import replace
from pathlib import Path
from typing import Any

from league import nights
from league.assembler import assemble
from league.bracket_nights import draw_night_bracket, record_match
from league.corrections import disqualify_lap, rename_racer
from league.head_to_heads import record_head_to_head
from league.seasons import new_season, parse_points
from league.store import League
from league.submissions import submit
from league.sync.record import SyncRecord
from racer_tui.cli.main import main
from sim.foundation.ids import new_id
from sim.race.driver import reference_driver
from sim.race.head_to_head import Entry, HeadToHeadResult, run_head_to_head
from sim.race.result import RaceResult
from sim.race.rules import HEAD_TO_HEAD_RULES, RaceRules, RankingMethod
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track
from tests.league.helpers import TRACK, model_folder, race_result

NIGHT_LAPS = {"ana": [11.0, 10.6, 10.9], "bob": [10.8, 10.7], "cy": [12.0, 12.0]}
RULES = RaceRules(window_seconds=60.0, ranking=RankingMethod.BEST_LAP)


def add_submissions(
    league: League, root: Path, entries: Sequence[tuple[str, Sequence[float]]]
) -> list[str]:
    """Submit one model folder per (racer, lap times); returns the submission ids."""
    ids = []
    for number, (racer, laps) in enumerate(entries):
        folder = model_folder(root / new_id(), f"car-{number}", laps=laps)
        ids.append(submit(league, assemble(str(folder), racer)).submission_id)
    return ids


def _fake_engine(
    track: Track, rules: RaceRules, driver: Any, *, racer: str, seed: int
) -> RaceResult:
    return race_result(racer, NIGHT_LAPS[racer], track=track, rules=rules, model=str(driver))


def host_league(league: League, root: Path) -> None:
    """What a league host's machine holds: a season with a closed night (an entrant
    withdrawn before the draw, a bracket of its best two), a night deleted before it was
    held, corrections."""
    new_season(league, "spring", parse_points("10,6,4"))
    night = nights.new_night(
        league, resolve_track(TRACK), rules=RULES, name="Friday", season="spring"
    )
    for racer in NIGHT_LAPS:
        nights.add_entrant(league, night, racer, "reference")
    late = nights.add_entrant(league, night, "ana", "physical")
    nights.withdraw_entrant(league, night, late.id, "host")  # entered by mistake
    nights.draw_heats(league, night, seed=3)
    races = nights.run_heats(
        league, night, resolve_track(TRACK), lambda spec, _track: spec, run_race=_fake_engine
    )
    # A bracket of the two best qualifiers, its one match won by the first seed: the night's
    # places stay its qualifying's.
    drawn = draw_night_bracket(
        league, night, size=2, rules=replace(HEAD_TO_HEAD_RULES, lap_count=1)
    )
    seeds = [drawn.racers[entrant] for entrant in drawn.bracket.seeds]
    record_match(league, night, "W1-1", head_to_head(*seeds))
    nights.close_night(league, night, "host")
    never_held = nights.new_night(league, resolve_track(TRACK), rules=RULES, name="Saturday")
    nights.delete_night(league, never_held, "host")
    disqualify_lap(league, races[0], 1, reason="cut the chicane", by="host")
    submitted = add_submissions(league, root, [("ana", (12.0, 12.5)), ("bob", (11.9,))])
    disqualify_lap(league, submitted[1], 1, reason="wrong track", by="host")
    rename_racer(league, "cy", "Cyrus", by="host")
    record_head_to_head(league, head_to_head("ana", "bob"))


def head_to_head(*racers: str, seed: int = 1) -> HeadToHeadResult:
    """A real one-lap head-to-head race of the reference driver against itself."""
    track = resolve_track(TRACK)
    driver = reference_driver(track)
    rules = replace(HEAD_TO_HEAD_RULES, lap_count=1)
    return run_head_to_head(track, rules, [Entry(racer, driver) for racer in racers], seed=seed)


def found_store(url: str, root: Path) -> None:
    """What the organiser's `racer-tui sync init` does: found the league on this machine's
    key and push the founding record. Every league in a test shares one data directory,
    so one key: the organiser's, whose records every league accepts."""
    from league.opening import open_league
    from league.sync.engine import push, store_key
    from league.sync.stores import open_store
    from league.trust.keys import load_or_create_key
    from league.trust.membership import found_league

    with open_league(root / "organiser.db") as league, open_store(url) as store:
        found_league(league, load_or_create_key())
        push(league, store, store_key(url))


def sealed(*records: SyncRecord) -> list[SyncRecord]:
    """Records signed with this test's key (the organiser's), as a push would send them."""
    from league.trust.keys import load_or_create_key
    from league.trust.seals import make_seal

    key = load_or_create_key()
    return [record.sealed(make_seal(record, key)) for record in records]


def cli(*args: str) -> str:
    out = io.StringIO()
    with redirect_stdout(out):
        code = main(list(args))
    assert code == 0, out.getvalue()
    return out.getvalue()


def views(league: League) -> dict[str, Any]:
    """Everything a racer sees of the league, through the CLI's JSON output."""
    db = str(league.path)
    seasons = json.loads(cli("season", "list", "--db", db, "--json"))
    return {
        "standings": [
            json.loads(cli("season", "show", season["id"], "--db", db, "--json"))
            for season in seasons
        ],
        "leaderboard": json.loads(cli("leaderboard", "--db", db, "--format", "json")),
        "average": json.loads(
            cli("leaderboard", "--db", db, "--format", "json", "--by", "average")
        ),
        "racers": json.loads(cli("racer", "list", "--db", db, "--json")),
        "seasons": json.loads(cli("season", "list", "--db", db, "--json")),
        "nights": json.loads(cli("night", "list", "--db", db, "--json")),
        "corrections": json.loads(cli("correct", "list", "--db", db, "--json")),
    }


def shared_rows(league: League) -> dict[str, set[tuple[str, str]]]:
    """(id, content hash) of every shared row, table by table."""
    from league.records import SHARED_TABLES

    return {
        table: {(row[0], row[1]) for row in league.query(f"SELECT id, content_hash FROM {table}")}
        for table in SHARED_TABLES
    }

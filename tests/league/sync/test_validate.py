"""Pulled records are checked kind by kind before they touch the database: every record a
real league makes passes, and each broken rule is refused with a sentence naming it."""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from league.opening import open_league
from league.records import SHARED_TABLES
from league.store import League
from league.sync.errors import RecordInvalidError
from league.sync.kinds import KIND_OF_TABLE, LEAGUE_KINDS, TABLE_OF_KIND, profile_id
from league.sync.outgoing import unsent_batches
from league.sync.record import SyncRecord, make_record
from league.sync.validate import FIELDS, LAP_FIELDS, check_record
from league.trust.keys import load_or_create_key
from league.trust.membership import found_league
from sim.foundation.ids import is_valid_id
from tests.league.sync.leagues import add_submissions, host_league


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, SyncRecord]]:
    """One record of every league kind, as a real league made it."""
    root = tmp_path_factory.mktemp("made")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RACER_TUI_HOME", str(root / "home"))
        with open_league(root / "league.db") as league:
            found_league(league, load_or_create_key())
            host_league(league, root)
            add_submissions(league, root, [("[bold red]x", (11.0,))])
            records = [r for batch in unsent_batches(league, "nowhere") for r in batch.records]
    yield {record.kind: record for record in records}


def test_every_shared_table_has_one_kind_with_its_exact_columns(league: League) -> None:
    assert set(TABLE_OF_KIND.values()) == set(SHARED_TABLES)
    assert tuple(KIND_OF_TABLE[table] for table in SHARED_TABLES) == LEAGUE_KINDS
    for kind, table in TABLE_OF_KIND.items():
        columns = {
            row["name"]: (row["type"], not row["notnull"])
            for row in league.query(f"PRAGMA table_info({table})")
            if row["name"] not in ("id", "content_hash")
        }
        declared = {name: (spec.sql_type, spec.nullable) for name, spec in FIELDS[kind].items()}
        assert declared == columns, kind
    for kind, children in (("submission", "submission_laps"), ("race", "race_laps")):
        columns = {
            row["name"]: (row["type"], not row["notnull"])
            for row in league.query(f"PRAGMA table_info({children})")
            if row["name"] not in ("submission_id", "race_id")
        }
        assert {n: (s.sql_type, s.nullable) for n, s in LAP_FIELDS[kind].items()} == columns


def test_every_record_a_league_makes_passes(made: dict[str, SyncRecord]) -> None:
    assert set(made) == set(LEAGUE_KINDS)
    for record in made.values():
        check_record(record)
    check_record(
        make_record(
            "racer_profile",
            profile_id("Ana"),
            {"racer": "ana", "display_name": "Ana B", "correction": made["correction"].record_id},
            1,
        )
    )


def test_profile_ids_are_valid_ids_and_ignore_case() -> None:
    assert is_valid_id(profile_id("[bold red]x"))
    assert profile_id("Ana") == profile_id("ana") != profile_id("anna")


Change = Callable[[dict[str, Any]], None]


def _set(key: str, value: Any) -> Change:
    return lambda body: body.__setitem__(key, value)


def _lap(key: str, value: Any) -> Change:
    return lambda body: body["laps"][0].__setitem__(key, value)


def _rules(change: dict[str, Any]) -> Change:
    def apply(body: dict[str, Any]) -> None:
        body["rules"] = json.dumps({**json.loads(body["rules"]), **change})

    return apply


def _cars(change: Callable[[list[dict[str, Any]]], None]) -> Change:
    def apply(body: dict[str, Any]) -> None:
        cars = json.loads(body["cars"])
        change(cars)
        body["cars"] = json.dumps(cars)

    return apply


def _car(key: str, value: Any) -> Change:
    return _cars(lambda cars: cars[1].__setitem__(key, value))


def _incidents(incidents: list[dict[str, Any]]) -> Change:
    return _set("incidents", json.dumps(incidents))


CASES: list[tuple[str, Change, str]] = [
    ("racer", _set("name", " ana"), "its name is not a name"),
    ("racer", _set("display_name", "two\nlines"), "its display_name is not a name"),
    ("racer", _set("colour", "red"), "#rrggbb"),
    ("racer", _set("created_at", "2026-01-01T00:00:00"), "UTC offset"),
    ("racer", _set("extra", 1), "has unknown extra"),
    ("track", _set("track_hash", "abc"), "SHA-256"),
    ("season", _set("points", "[1, 5]"), "points table"),
    ("season", _set("points", "not json"), "not valid JSON"),
    ("night", _rules({"window_seconds": -1}), "are not race rules"),
    ("night", _set("season_id", "../../etc"), "not a record id"),
    ("night", _set("held_on", "2026-02-30"), "held_on is not a date"),
    ("night", _set("held_on", "20260201"), "held_on is not a date"),
    ("night", _set("held_on", "2026-W10-5"), "held_on is not a date"),
    ("night", _rules({"lap_count": 0}), "are not race rules"),
    ("heat", _set("draw_seed", True), "draw_seed is not a whole number"),
    ("submission", _lap("time_seconds", 12), "is not a decimal number"),
    ("submission", _lap("completion", 150.0), "from 0 to 100"),
    ("submission", _lap("number", 7), "lap 1 is numbered 7"),
    ("submission", _set("source", "elsewhere"), "is not one of"),
    ("submission", lambda body: body.pop("fingerprint"), "lacks fingerprint"),
    ("submission", _set("laps", {"number": 1}), "are not a list"),
    ("race", _lap("time_seconds", 99.0), "not a valid race result"),
    ("race", _set("total_offtracks", 10**12), "total_offtracks is not a whole number"),
    ("race", _set("runtime", "x" * 101), "runtime is not"),
    ("race", _set("runtime", 7), "runtime is not"),
    ("head_to_head", _rules({"race_type": "TIME_TRIAL"}), "are not a head-to-head race's"),
    ("head_to_head", _cars(lambda cars: cars.pop()), "are not a list of 2 to 6 cars"),
    ("head_to_head", _cars(lambda cars: cars.extend(cars * 3)), "are not a list of 2 to 6"),
    ("head_to_head", _car("car", 0), "hold grid slot 1 twice"),
    ("head_to_head", _car("racer", "two\nlines"), "car in place 2: its racer is not a name"),
    ("head_to_head", _car("laps_completed", 7), "counts other laps than it holds"),
    ("head_to_head", _car("gap_seconds", -3.0), "gap_seconds is not"),
    ("head_to_head", _car("runtime", None), "runtime is null instead of left out"),
    ("head_to_head", _car("pit_stops", 2), "has unknown pit_stops"),
    (
        "head_to_head",
        _cars(lambda cars: cars[0]["laps"][0].__setitem__(1, 99.0)),
        "not a valid race result",
    ),
    (
        "head_to_head",
        _cars(lambda cars: cars[0]["laps"][0].__setitem__(slice(1, 4), [0.5, 0.5, 0.0])),
        "faster than any car can go round",
    ),
    (
        "head_to_head",
        _incidents([{"clock": 1.0, "kind": "crash", "car": 0, "other": 4}]),
        "not in the race",
    ),
    (
        "head_to_head",
        _incidents([{"clock": 1.0, "kind": "bump", "car": 0, "other": 1}]),
        "is not one of",
    ),
    (
        "head_to_head",
        _incidents([{"clock": 1.0, "kind": "crash", "car": 0, "other": 1}] * 401),
        "incidents are not a list of at most 400",
    ),
    ("head_to_head", _set("match_id", "semi-final"), "is not a bracket match"),
    ("head_to_head", _set("match_id", "W1-1"), "names a bracket match of no night"),
    ("head_to_head", _car("laps", [[1, 9.0]]), "are not lists of a lap's 9 values"),
    ("head_to_head", _set("physics", None), "physics is missing"),
    ("bracket", _rules({"race_type": "TIME_TRIAL"}), "are not a head-to-head race's"),
    ("bracket", _set("format", "triple"), "is not one of"),
    ("bracket", _set("seeds", json.dumps(["01M7YFZPX152TMAJ036HERQM71"])), "2 to 64 entrants"),
    ("bracket", _set("seeds", json.dumps(["../x", "01M7YFZPX152TMAJ036HERQM71"])), "entrant's id"),
    ("bracket", _set("seeds", json.dumps(["01M7YFZPX152TMAJ036HERQM71"] * 2)), "entrant twice"),
    ("bracket", _set("seeds", json.dumps({"a": 1})), "are not a list"),
    ("bracket", _set("night_id", None), "night_id is"),
    (
        "correction",
        lambda body: body.update(
            kind="disqualify_lap", target="01M7YFZPX152TMAJ036HERQM71", new_value=None
        ),
        "needs a lap number",
    ),
    ("correction", _set("target", "two\nlines"), "its target is not a name"),
    ("correction", _set("kind", "delete_everything"), "is not one of"),
]


@pytest.mark.parametrize(("kind", "change", "reason"), CASES)
def test_a_broken_rule_is_refused_with_its_reason(
    made: dict[str, SyncRecord], kind: str, change: Change, reason: str
) -> None:
    original = made[kind]
    body = copy.deepcopy(original.body)
    change(body)
    with pytest.raises(RecordInvalidError, match=reason):
        check_record(make_record(kind, original.record_id, body))


def test_sync_level_kinds_are_checked_too() -> None:
    profile = {"racer": "ana", "display_name": "Ana", "correction": "01M7YFZPX152TMAJ036HERQM71"}
    with pytest.raises(RecordInvalidError, match="profile id"):
        check_record(make_record("racer_profile", profile_id("bob"), profile, 1))
    bundle = {"model_hash": "a" * 64, "sha256": "b" * 64, "size": 10, "name": "../escape"}
    with pytest.raises(RecordInvalidError, match="model name"):
        check_record(make_record("bundle", "01M7YFZPX152TMAJ036HERQM71", bundle))


def test_outgoing_bodies_are_the_leagues_own(tmp_path: Path, league: League) -> None:
    from league.records import record_body

    host_league(league, tmp_path)
    for batch in unsent_batches(league, "nowhere", batch=3):
        for record in batch.records:
            assert record.body == record_body(league, TABLE_OF_KIND[record.kind], record.record_id)


def test_a_race_with_its_policy_runtime_passes(made: dict[str, SyncRecord]) -> None:
    original = made["race"]
    body = copy.deepcopy(original.body)
    body["runtime"] = "torch 2.13.0 x86_64 16caca443e89"
    check_record(make_record("race", original.record_id, body))

"""Verification by replay: races are deterministic, so re-running one from the model,
track, rules and seed it names must give its laps; a race that does not is withdrawn and
listed in quarantine, and one that cannot be re-run here is unverifiable with the reason."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from league.opening import open_league
from league.races import race_result, record_race
from league.records import record_body
from league.store import League
from league.trust.replay import verify_races
from league.trust.standing import Standing, result_standings
from racer_tui.cli.main import main
from sim.foundation.ids import new_id
from sim.garage.options import new_model
from sim.race.driver import reference_driver
from sim.race.engine import run_race
from sim.race.result import RaceResult
from sim.race.rules import RaceRules
from sim.tracks.catalog import resolve_track
from sim.training.drivers import DriversByHash
from sim.training.policy import build_network, policy_runtime, save_policy

RULES = RaceRules(window_seconds=40.0)


def _reference_race(league: League, racer: str, seed: int) -> str:
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RULES, reference_driver(track), racer=racer, seed=seed)
    return record_race(league, result)


def _forged_race(league: League) -> str:
    """A race that claims a lap 0.8 s faster than the car drove it."""
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RULES, reference_driver(track), racer="mallory", seed=9)
    first = result.laps[0]
    quicker = replace(
        first, time_seconds=first.time_seconds - 0.8, raw_seconds=first.raw_seconds - 0.8
    )
    return record_race(league, replace(result, laps=(quicker, *result.laps[1:])))


def test_a_true_race_verifies_and_a_forged_one_is_withdrawn(tmp_path: Path) -> None:
    with open_league(tmp_path / "league.db") as league:
        honest = _reference_race(league, "ana", seed=4)
        forged = _forged_race(league)
        verdicts = {v.race_id: v for v in verify_races(league, DriversByHash())}

        assert verdicts[honest].outcome == "same"
        assert verdicts[forged].outcome == "differs"
        assert "lap 1 has raw seconds" in verdicts[forged].detail
        assert [row[0] for row in league.query("SELECT id FROM races")] == [honest]
        assert "mallory" not in {row["racer"] for row in league.query("SELECT racer FROM board")}
        (row,) = league.query("SELECT location, reason FROM sync_quarantine")
        assert row["location"] == f"race {forged}"
        assert row["reason"].startswith("it is racer mallory's, but re-run here, its lap 1")

        assert verify_races(league, DriversByHash()) == []  # verified races are not re-run
        assert [v.outcome for v in verify_races(league, DriversByHash(), again=True)] == ["same"]


def test_a_race_that_claims_a_reset_it_did_not_have_differs(tmp_path: Path) -> None:
    track = resolve_track("hairpin-circuit")
    result = run_race(track, RULES, reference_driver(track), racer="mallory", seed=3)
    claimed = replace(result.laps[0], reversals=1)  # same times: only the count is made up
    with open_league(tmp_path / "league.db") as league:
        race_id = record_race(league, replace(result, laps=(claimed, *result.laps[1:])))
        [verdict] = verify_races(league, DriversByHash())
    assert (verdict.race_id, verdict.outcome) == (race_id, "differs")
    assert "lap 1 has 0 reversals, not the 1 it claims" in verdict.detail


def test_a_race_whose_model_is_not_here_is_unverifiable_with_how_to_fetch_it(
    tmp_path: Path,
) -> None:
    with open_league(tmp_path / "league.db") as league:
        track = resolve_track("hairpin-circuit")
        result = run_race(track, RULES, reference_driver(track), racer="bob", seed=2)
        record_race(league, replace(result, model_hash="ab" * 32, model_name="bobs-car"))
        (verdict,) = verify_races(league, DriversByHash())
        assert verdict.outcome == "unverifiable"
        assert verdict.detail == (
            "its model abababababab is not in this garage, so it cannot be re-run here "
            "(racer-tui sync fetch-bundle installs it, if its racer shared it)"
        )
        assert len(league.query("SELECT id FROM races")) == 1  # not withdrawn
        # Tried again on the next run: the model may have been fetched since.
        assert [v.outcome for v in verify_races(league, DriversByHash())] == ["unverifiable"]


def test_a_race_of_other_physics_or_a_physical_car_is_unverifiable_here(tmp_path: Path) -> None:
    with open_league(tmp_path / "league.db") as league:
        track = resolve_track("hairpin-circuit")
        result = run_race(track, RULES, reference_driver(track), racer="bob", seed=2)
        older = record_race(league, replace(result, physics="racer-tui/1"))
        by_hand = record_race(league, replace(result, physics="physical", result_id=new_id()))
        verdicts = {v.race_id: v for v in verify_races(league, DriversByHash())}
    assert verdicts[older].outcome == verdicts[by_hand].outcome == "unverifiable"
    assert verdicts[older].detail.startswith(
        "it was timed with racer-tui/1 and this racer-tui drives racer-tui/"
    )
    assert verdicts[by_hand].detail == (
        "its laps were timed by hand on a real track, so it cannot be re-run here"
    )


def test_a_verdict_stored_as_skipped_opens_as_unverifiable(tmp_path: Path) -> None:
    """A league from before the word changed: its remembered verdicts are renamed by a
    migration when it is opened, and nothing else of them changes."""
    import sqlite3

    from league.migrations import MIGRATIONS

    before = next(i for i, m in enumerate(MIGRATIONS) if m.description == "unverifiable replays")
    db = tmp_path / "league.db"
    conn = sqlite3.connect(db)
    for migration in MIGRATIONS[:before]:
        migration.apply(conn)
    conn.execute(
        "INSERT INTO sync_replays VALUES ('01M8JX393J9JBZ9KJEMTPZ5FMH', 'h', 'skipped', "
        "'its model is not in this garage', '2026-01-01T00:00:00.000Z')"
    )
    conn.execute(f"PRAGMA user_version = {before}")
    conn.commit()
    conn.close()
    with open_league(db) as league:
        (row,) = league.query("SELECT outcome, detail FROM sync_replays")
    assert (row[0], row[1]) == ("unverifiable", "its model is not in this garage")


def test_sync_verify_reports_in_text_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "league.db"
    with open_league(db) as league:
        _reference_race(league, "ana", seed=1)
        forged = _forged_race(league)
    assert main(["sync", "verify", "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("Re-ran 2 races: 1 the same, 1 different (withdrawn")
    assert "; 0 unverifiable here." in out
    assert f"differs: race {forged} (mallory)" in out
    assert main(["sync", "verify", "--again", "--db", str(db), "--json"]) == 0
    (again,) = json.loads(capsys.readouterr().out)
    assert again["outcome"] == "same"


def _camera_model_race(racer: str) -> tuple[RaceResult, str]:
    """A race of a garage camera model (an untrained policy: it drives all the same)."""
    folder = new_model("cam", sensors=["camera"], track="hairpin-circuit")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    track = resolve_track("hairpin-circuit")
    driver = DriversByHash()(folder.content_hash(), track)
    assert driver is not None
    return run_race(track, RULES, driver, racer=racer, seed=5), policy_runtime()


def test_a_race_is_judged_only_under_the_policy_runtime_that_drove_it(tmp_path: Path) -> None:
    result, runtime = _camera_model_race("ana")
    assert result.runtime == runtime and runtime.startswith("torch ")
    other = replace(result, result_id=new_id(), runtime="torch 2.13.0 arm64 0123456789ab")
    with open_league(tmp_path / "league.db") as league:
        here = record_race(league, result)
        elsewhere = record_race(league, other)
        # The runtime travels with the race and comes back with it.
        assert record_body(league, "races", here)["runtime"] == runtime
        verdicts = {v.race_id: v for v in verify_races(league, DriversByHash())}
        assert verdicts[here].outcome == "same"
        assert verdicts[elsewhere].outcome == "unverifiable"
        assert verdicts[elsewhere].detail == (
            "its policy ran on the numerics of torch 2.13.0 arm64 0123456789ab and this "
            f"machine's are {runtime}, so it cannot be re-run here"
        )
        assert len(league.query("SELECT id FROM races")) == 2  # nobody is withdrawn
        # Every board says so too, though its model is here.
        standing = result_standings(league, [here, elsewhere], {result.model_hash})
        assert standing[here].standing is Standing.REPLAYED
        assert standing[elsewhere].standing is Standing.UNVERIFIABLE
        assert standing[elsewhere].why.startswith("its policy ran on the numerics of torch")


def test_a_reference_race_has_no_runtime_and_keeps_its_record_as_before(tmp_path: Path) -> None:
    with open_league(tmp_path / "league.db") as league:
        race_id = _reference_race(league, "ana", seed=4)
        assert "runtime" not in record_body(league, "races", race_id)
        assert race_result(league, race_id).runtime == ""


def _cli(*args: str, isa: str) -> str:
    """racer-tui in a process of its own with oneDNN held to instruction set `isa`."""
    done = subprocess.run(
        [sys.executable, "-m", "racer_tui.cli.main", *args],
        env={**os.environ, "ONEDNN_MAX_CPU_ISA": isa},
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.slow
def test_a_camera_race_replays_exactly_under_the_kernels_that_drove_it(tmp_path: Path) -> None:
    """Recorded under two of the kernel levels this machine offers (oneDNN's convolutions
    on SSE4.1, and on the best it has): each replays the same under its own level, and is
    unverifiable, never withdrawn, under the other."""
    folder = new_model("cam", sensors=["camera"], track="hairpin-circuit")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    db = str(tmp_path / "league.db")
    race = ["--race", "cam", "--track", "hairpin-circuit", "--window", "20", "--record"]
    for isa in ("SSE41", "ALL"):
        _cli(*race, "--racer", f"ana-{isa.lower()}", "--db", db, isa=isa)
    with open_league(Path(db)) as league:
        rows = league.query("SELECT racer, runtime FROM races")
    runtimes = {row["racer"]: row["runtime"] for row in rows}
    assert runtimes["ana-sse41"] != runtimes["ana-all"]  # the level is in the runtime
    for isa in ("SSE41", "ALL"):
        verdicts = json.loads(_cli("sync", "verify", "--again", "--db", db, "--json", isa=isa))
        outcomes = {verdict["racer"]: verdict["outcome"] for verdict in verdicts}
        own = f"ana-{isa.lower()}"
        other = "ana-all" if isa == "SSE41" else "ana-sse41"
        assert outcomes == {own: "same", other: "unverifiable"}
    with open_league(Path(db)) as league:
        assert len(league.query("SELECT id FROM races")) == 2

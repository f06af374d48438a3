"""Verification by replay: races are deterministic, so re-running one from the model,
track, rules and seed it names must give its laps; a race that does not is withdrawn and
listed in quarantine, and one that cannot be re-run here is unverifiable with the reason."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
import torch

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
from sim.training.policy import build_network, save_policy
from sim.training.policy_driver import PolicyDriver
from sim.training.runtimes import TORCH_CAMERA, VERSIONS, policy_runtime, policy_runtimes

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
    assert result.runtime == runtime and runtime.startswith("v2 numpy ")
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


def test_a_race_driven_under_an_earlier_runtime_version_replays_under_it(
    tmp_path: Path,
) -> None:
    """Races recorded before runtime version 2 (camera networks in torch) keep replaying
    exactly: the replay drives the model under the version its record names, though the
    garage's driver drives under the current one; a false claim under it is still found."""
    folder = new_model("cam", sensors=["camera"], track="hairpin-circuit")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    track = resolve_track("hairpin-circuit")
    driver = DriversByHash()(folder.content_hash(), track)
    assert isinstance(driver, PolicyDriver) and driver.runtime == policy_runtime()
    then = driver.under(policy_runtimes()[TORCH_CAMERA])
    assert then is not None
    old = run_race(track, RULES, then, racer="ana", seed=5)
    assert old.runtime == policy_runtimes()[TORCH_CAMERA]
    # A lap it never drove, claimed under the same runtime, numbered after its own: the
    # untrained network's weights are drawn afresh each run, and some runs finish a lap.
    driven = run_race(track, RULES, reference_driver(track), racer="x", seed=5).laps[0]
    extra = replace(driven, number=max((lap.number for lap in old.laps), default=0) + 1)
    claimed = replace(old, result_id=new_id(), racer="mallory", laps=(*old.laps, extra))
    with open_league(tmp_path / "league.db") as league:
        honest, forged = record_race(league, old), record_race(league, claimed)
        verdicts = {v.race_id: v for v in verify_races(league, DriversByHash())}
    assert verdicts[honest].outcome == "same"
    assert verdicts[honest].runtime_here == policy_runtimes()[TORCH_CAMERA]
    assert verdicts[forged].outcome == "differs"


# One process a level says both what it computes (`python -m sim.training.runtimes`'s
# names) and what `sync verify --again` finds there: the kernel levels are fixed when the
# libraries load, and a process each would load torch twice a level.
_RUNTIMES_THEN_VERIFY = """
import json, sys
from racer_tui.cli.main import main
from sim.training.runtimes import policy_runtimes
print(json.dumps(policy_runtimes()), flush=True)
sys.exit(main(["sync", "verify", "--again", "--db", sys.argv[1], "--json"]))
"""


def _runtimes_and_verdicts(
    db: Path, env: dict[str, str]
) -> tuple[dict[str, str], list[dict[str, str]]]:
    """This machine's runtime names and the league's verdicts, under `env`'s kernel levels."""
    names, verdicts = _run("-c", _RUNTIMES_THEN_VERIFY, str(db), env=env).split("\n", 1)
    return json.loads(names), json.loads(verdicts)


def _run(*args: str, env: dict[str, str]) -> str:
    """Python run in a process of its own (`args` after `python`), under `env`'s kernel
    levels."""
    done = subprocess.run(
        [sys.executable, *args],
        env={**os.environ, **env},
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def _kernel_levels() -> list[dict[str, str]]:
    """Each kernel level torch offers on this machine (ATEN_CPU_CAPABILITY, up to its
    own), and oneDNN's convolutions and OpenBLAS's products held to their oldest x86
    kernels (the libraries a policy computes with)."""
    order = ["default", "avx2", "avx512"]
    best = torch.backends.cpu.get_cpu_capability().lower()
    levels = [{"ATEN_CPU_CAPABILITY": level} for level in order[: order.index(best) + 1]]
    if platform.machine() in {"x86_64", "AMD64"}:
        levels += [{"ONEDNN_MAX_CPU_ISA": "SSE41"}, {"OPENBLAS_CORETYPE": "Prescott"}]
    return levels


@pytest.mark.slow
def test_camera_races_replay_exactly_under_each_kernel_level_that_has_their_runtime(
    tmp_path: Path,
) -> None:
    """A camera race of each runtime version, replayed under each kernel level: the same
    wherever the level computes the runtime that drove it, unverifiable (never withdrawn)
    wherever it does not."""
    folder = new_model("cam", sensors=["camera"], track="hairpin-circuit")
    save_policy(folder.policy_file, build_network(folder.metadata()))
    track = resolve_track("hairpin-circuit")
    driver = DriversByHash()(folder.content_hash(), track)
    assert isinstance(driver, PolicyDriver)
    drivers = {version: driver.under(policy_runtimes()[version]) for version in VERSIONS}
    db = tmp_path / "league.db"
    with open_league(db) as league:
        raced = {
            record_race(league, run_race(track, RULES, found, racer=f"v{version}", seed=5))
            for version, found in drivers.items()
            if found is not None
        }
    assert len(raced) == len(VERSIONS)
    names_of_levels = []
    for env in _kernel_levels():
        names, verdicts = _runtimes_and_verdicts(db, env)
        names_of_levels.append(set(names.values()))
        outcomes = {v["racer"]: v["outcome"] for v in verdicts}
        for version in VERSIONS:
            expected = "same" if policy_runtimes()[version] in names.values() else "unverifiable"
            assert outcomes[f"v{version}"] == expected, (env, version)
    # The machine's own level computes both; oneDNN's oldest convolutions give version 1
    # another name (measured on x86 machines), so a level that is not the race's is met.
    assert names_of_levels[0] >= set(policy_runtimes().values())
    if platform.machine() in {"x86_64", "AMD64"}:
        assert policy_runtimes()[TORCH_CAMERA] not in names_of_levels[-2]
    with open_league(db) as league:
        assert len(league.query("SELECT id FROM races")) == len(VERSIONS)

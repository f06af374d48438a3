"""Each result's standing here (replayed, verifiable, unverifiable), the boards that show it
and rank by it, and a night under a verification rule: its heats raced again at close, and
the heats the rule leaves out said one sentence each."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from league import nights
from league.assembler import assemble
from league.leaderboard import Filters, leaderboard, mark_verification
from league.night_verification import uncounted_heats
from league.races import record_race
from league.ranking import counts_under
from league.store import League
from league.submissions import submit
from league.trust.replay import verify_races
from league.trust.standing import Standing, result_standings
from racer_tui.cli.main import main
from sim.foundation.ids import new_id
from sim.physics.labels import PHYSICAL
from sim.race.driver import reference_driver
from sim.race.engine import run_race
from sim.race.result import RaceResult
from sim.race.rules import RaceRules, RankingMethod, Verification
from sim.tracks.catalog import resolve_track
from sim.tracks.track import Track
from sim.training.drivers import DriversByHash

TRACK = "hairpin-circuit"
RULES = RaceRules(window_seconds=40.0)
MADE_UP = "ab" * 32


def _reference(racer: str, seed: int, rules: RaceRules = RULES) -> RaceResult:
    track = resolve_track(TRACK)
    return run_race(track, rules, reference_driver(track), racer=racer, seed=seed)


def _faster(result: RaceResult, by: float) -> RaceResult:
    laps = tuple(
        replace(lap, time_seconds=lap.time_seconds - by, raw_seconds=lap.raw_seconds - by)
        for lap in result.laps
    )
    return replace(result, laps=laps, result_id=new_id())


def _physical(result: RaceResult) -> RaceResult:
    return replace(result, physics=PHYSICAL, model_hash="physical", result_id=new_id())


def test_each_kind_of_result_has_its_standing(league: League, deepracer_dir: Path) -> None:
    replayed = record_race(league, _reference("ana", seed=1))
    verify_races(league, DriversByHash())
    not_yet = record_race(league, _reference("bob", seed=2))
    in_garage = record_race(league, replace(_reference("cy", seed=3), model_hash="cd" * 32))
    shared = record_race(league, replace(_reference("dee", seed=4), model_hash="ef" * 32))
    league.conn.execute(
        "INSERT INTO sync_bundles (record_id, model_hash, sha256, size, name, content_hash) "
        "VALUES (?, ?, ?, 1, 'dees-car', 'x')",
        (new_id(), "ef" * 32, "0" * 64),
    )
    made_up = record_race(league, replace(_reference("eve", seed=5), model_hash=MADE_UP))
    by_hand = record_race(league, _physical(_reference("fay", seed=6)))
    older = record_race(league, replace(_reference("gus", seed=7), physics="racer-tui/1"))
    drfc = submit(
        league, assemble(str(deepracer_dir / "drfc-model"), "hal", track="reinvent_base")
    ).submission_id

    ids = [replayed, not_yet, in_garage, shared, made_up, by_hand, older, drfc]
    found = result_standings(league, ids, local_models={"cd" * 32})

    assert [found[i].standing for i in ids] == [
        Standing.REPLAYED,
        Standing.VERIFIABLE,  # the reference driver, not raced again yet
        Standing.VERIFIABLE,  # its model is in this garage
        Standing.VERIFIABLE,  # a racer shared its bundle
        Standing.UNVERIFIABLE,
        Standing.UNVERIFIABLE,
        Standing.UNVERIFIABLE,
        Standing.UNVERIFIABLE,
    ]
    assert found[made_up].why == "its model is not in this garage and no racer shared it"
    assert found[by_hand].why == "a physical car's laps, timed by hand on a real track"
    assert found[older].why.startswith("timed with racer-tui/1, and this racer-tui drives")
    assert found[drfc].why == "an evaluation submitted from files names no seed to race it again"
    # Without the garage's hashes, a model only in the garage is not known to be here.
    assert result_standings(league, [in_garage])[in_garage].standing is Standing.UNVERIFIABLE


def test_leaderboard_rows_carry_their_standing(league: League) -> None:
    record_race(league, _reference("ana", seed=1))
    verify_races(league, DriversByHash())
    record_race(league, replace(_reference("eve", seed=5), model_hash=MADE_UP))
    rows = leaderboard(league, Filters(), RankingMethod.BEST_LAP)
    assert {row.racer: row.verification for row in rows} == {"ana": "", "eve": ""}
    mark_verification(league, rows)
    assert {row.racer: row.verification for row in rows} == {
        "ana": "replayed",
        "eve": "unverifiable",
    }


@pytest.mark.parametrize(
    ("standing", "counted"),
    [
        ("replayed", {Verification.ANY, Verification.VERIFIABLE, Verification.REPLAYED}),
        ("verifiable", {Verification.ANY, Verification.VERIFIABLE}),
        ("unverifiable", {Verification.ANY}),
    ],
)
def test_which_standings_each_rule_ranks(standing: str, counted: set[Verification]) -> None:
    assert {level for level in Verification if counts_under(standing, level)} == counted


def test_a_board_of_replayed_results_ranks_a_racers_best_verified_race(league: League) -> None:
    """Eve's forged-looking best cannot be raced again; her slower replayed race still
    counts, before each racer's best is picked, and a racer with none is left out."""
    honest = _reference("eve", seed=1)
    record_race(league, honest)
    verify_races(league, DriversByHash())
    record_race(league, replace(_faster(honest, 1.0), model_hash=MADE_UP))
    record_race(league, replace(_reference("bob", seed=2), model_hash=MADE_UP))
    track = resolve_track(TRACK).content_hash

    def board(level: Verification) -> list[tuple[str, float | None]]:
        rows = leaderboard(league, Filters(track_hash=track, verification=level))
        return [(row.racer, row.best_lap) for row in rows]

    everyone = board(Verification.ANY)
    assert [racer for racer, _ in everyone] == ["eve", "bob"]
    assert everyone[0][1] == pytest.approx(min(lap.time_seconds for lap in honest.laps) - 1.0)
    replayed = board(Verification.REPLAYED)
    assert [racer for racer, _ in replayed] == ["eve"]
    assert replayed[0][1] == pytest.approx(min(lap.time_seconds for lap in honest.laps))
    assert board(Verification.VERIFIABLE) == replayed


# --- a night under a verification rule --------------------------------------------------------


def _night_with_heats(league: League, level: str) -> nights.Night:
    """A night of four heats: ana's true, bob's laps a second faster than his car drove
    them, dan's under a model nobody has, carol's physical car timed by hand."""
    track = resolve_track(TRACK)
    rules = replace(RULES, verification=Verification(level))
    night = nights.new_night(league, track, rules=rules, name="friday")
    for racer in ("ana", "bob", "dan"):
        nights.add_entrant(league, night, racer, "reference")
    nights.add_entrant(league, night, "carol", "physical:blue car")
    nights.draw_heats(league, night, seed=5)

    def race(track: Track, rules: RaceRules, driver: Any, *, racer: str, seed: int) -> Any:
        result = run_race(track, rules, driver, racer=racer, seed=seed)
        if racer == "bob":
            return _faster(result, 1.0)
        return replace(result, model_hash=MADE_UP) if racer == "dan" else result

    nights.run_heats(league, night, track, lambda spec, t: reference_driver(t), run_race=race)
    (carol,) = nights.timekept_heats(league, night)
    timed = _physical(_reference("carol", seed=9, rules=rules))
    record_race(league, timed, night.id, heat_id=carol.id)
    return nights.get_night(league, night.id)


def _placed(standings: list[nights.Standing]) -> list[str]:
    return [s.entry.racer for s in standings if s.position is not None]


def test_before_close_a_replayed_night_counts_only_what_was_raced_again(league: League) -> None:
    night = _night_with_heats(league, "replayed")
    assert _placed(nights.standings(league, night)) == []
    sentences = uncounted_heats(league, night)
    assert len(sentences) == 4
    assert all("and this night counts only results verified by replay." in s for s in sentences)
    verifiable = _night_with_heats(league, "verifiable")
    # The reference driver can race ana's and bob's heats again here: they count until then.
    assert sorted(_placed(nights.standings(league, verifiable))) == ["ana", "bob"]
    # With dan's model in this garage, his heat can be raced again here too.
    here = nights.standings(league, verifiable, local_models={MADE_UP})
    assert sorted(_placed(here)) == ["ana", "bob", "dan"]
    assert len(uncounted_heats(league, verifiable, {MADE_UP})) == 1  # carol's, by hand


def test_closing_a_replayed_night_races_its_heats_again_first(league: League) -> None:
    night = _night_with_heats(league, "replayed")
    standings = nights.close_night(league, night, "host", force=True, driver_for=DriversByHash())

    assert _placed(standings) == ["ana"]  # bob's heat withdrawn; dan's and carol's left out
    assert [s.entry.racer for s in standings] == ["ana"]
    assert league.query_one(
        "SELECT reason FROM sync_quarantine WHERE reason LIKE 'it is racer bob''s, but re-run%'"
    )
    said = uncounted_heats(league, nights.get_night(league, night.id))
    assert [s.split(" does not count: ")[1] for s in said] == [
        "it is unverifiable (its model is not in this garage and no racer shared it), "
        "and this night counts only results verified by replay.",
        "it is unverifiable (a physical car's laps, timed by hand on a real track), "
        "and this night counts only results verified by replay.",
    ]


def test_night_close_says_each_heat_withdrawn_or_left_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    from league.opening import open_league

    db = tmp_path / "league.db"
    with open_league(db) as league:
        night = _night_with_heats(league, "replayed")
    # bob's heat is withdrawn, so it waits to be raced again: closing says so, and why.
    assert main(["night", "close", night.id, "--db", str(db)]) == 2
    out, err = capsys.readouterr()
    (withdrawn,) = out.splitlines()
    assert withdrawn.startswith("heat ") and "(bob, reference) is withdrawn: re-run here" in out
    assert "still has 1 heat to run" in err

    assert main(["night", "close", night.id, "--force", "--db", str(db)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert sum("does not count: it is unverifiable" in line for line in lines) == 2
    assert "(dan, reference) does not count" in out
    assert "(carol, blue car (physical)) does not count" in out
    assert "verification" in out and "replayed" in out  # the standings' column

    assert main(["night", "show", night.id, "--json", "--db", str(db)]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert [(s["racer_name"], s["verification"]) for s in shown["standings"]] == [
        ("ana", "replayed")
    ]
    assert shown["rules"]["verification"] == "replayed"


def test_night_new_sets_the_rule_and_the_leaderboard_shows_and_filters_by_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    db = str(tmp_path / "league.db")
    args = ["night", "new", "--track", TRACK, "--verification", "verifiable", "--db", db]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "(only results verified or verifiable by replay)." in out

    from league.opening import open_league

    with open_league(Path(db)) as league:
        record_race(league, _reference("ana", seed=1))
        record_race(league, replace(_reference("eve", seed=5), model_hash=MADE_UP))

    def board(*more: str) -> list[tuple[str, str]]:
        assert main(["leaderboard", "--db", db, "--format", "json", *more]) == 0
        return [(row["racer"], row["verification"]) for row in json.loads(capsys.readouterr().out)]

    assert sorted(board()) == [("ana", "verifiable"), ("eve", "unverifiable")]
    assert board("--verification", "verifiable") == [("ana", "verifiable")]
    assert board("--verification", "replayed") == []
    assert main(["leaderboard", "--db", db]) == 0
    table = capsys.readouterr().out
    assert "verification" in table and "unverifiable" in table

"""The leaderboard: each racer's best entry per track, in the one ranking order, under
every ranking method, filtered and sorted; the cached board agrees with rank()."""

from __future__ import annotations

import csv
import io
import random
from dataclasses import replace

import pytest

from league.errors import LeagueError
from league.leaderboard import Filters, board_sql, leaderboard, sort_rows
from league.races import record_race
from league.ranking import rank
from league.report import leaderboard_columns, markdown_escape, to_csv, to_markdown
from league.store import League
from sim.race.result import RaceResult
from sim.race.rules import RaceRules, RankingMethod, score_laps
from sim.tracks.catalog import resolve_track
from tests.league.helpers import race_result


def _board(
    league: League,
    method: RankingMethod = RankingMethod.BEST_LAP,
    *,
    track_hash: str | None = None,
    racer: str | None = None,
) -> list[tuple[int, str, float | None]]:
    rows = leaderboard(league, Filters(track_hash=track_hash, racer=racer), method)
    return [(row.rank, row.racer, row.score) for row in rows]


def test_each_racer_appears_once_with_their_best_entry(league: League) -> None:
    record_race(league, race_result("ana", [12.0, 11.5], model="slow"))
    record_race(league, race_result("ana", [11.0, 11.8], model="fast"))
    record_race(league, race_result("bob", [11.2, 11.3]))
    rows = leaderboard(league, Filters())
    assert [(row.rank, row.racer, row.model, row.best_lap) for row in rows] == [
        (1, "ana", "fast", 11.0),
        (2, "bob", "car", 11.2),
    ]


def test_ranking_methods_change_the_order(league: League) -> None:
    record_race(league, race_result("steady", [11.0, 11.0, 11.0]))
    record_race(league, race_result("flash", [10.0, 13.0, 13.0]))
    assert _board(league, RankingMethod.BEST_LAP) == [(1, "flash", 10.0), (2, "steady", 11.0)]
    assert _board(league, RankingMethod.BEST_AVERAGE) == [(1, "steady", 11.0), (2, "flash", 12.0)]
    assert _board(league, RankingMethod.TOTAL_TIME) == [(1, "steady", 33.0), (2, "flash", 36.0)]


def test_ties_break_on_offtracks_then_valid_laps_then_the_earlier_result(league: League) -> None:
    rules = RaceRules(penalty_seconds=0.0)
    record_race(
        league,
        race_result("late", [11.0, 12.0], rules=rules, started_at="2024-05-01T20:00:00.000Z"),
    )
    record_race(
        league,
        race_result("early", [11.0, 12.0], rules=rules, started_at="2024-05-01T19:00:00.000Z"),
    )
    record_race(
        league,
        race_result(
            "more-laps", [11.0, 12.0, 12.5], rules=rules, started_at="2024-05-01T21:00:00.000Z"
        ),
    )
    record_race(league, race_result("off", [11.0, 12.0], offtracks=[1], rules=rules))
    assert [racer for _, racer, _ in _board(league)] == ["more-laps", "early", "late", "off"]


def test_a_racer_with_no_valid_lap_ranks_last(league: League) -> None:
    record_race(league, race_result("crashy", [9.0], offtracks=[4]))
    record_race(league, race_result("careful", [15.0]))
    assert _board(league) == [(1, "careful", 15.0), (2, "crashy", None)]


def test_filters_by_track_and_racer(league: League) -> None:
    other = resolve_track("speedway")
    record_race(league, race_result("ana", [12.0]))
    record_race(league, race_result("ana", [14.0], track=other))
    record_race(league, race_result("bob", [13.0], track=other))
    assert _board(league, track_hash=other.content_hash) == [(1, "bob", 13.0), (2, "ana", 14.0)]
    assert _board(league, racer="ana") == [(1, "ana", 12.0), (1, "ana", 14.0)]
    everything = leaderboard(league, Filters())
    assert [(row.track_name, row.rank, row.racer) for row in everything] == [
        ("beginner-oval", 1, "ana"),
        ("speedway", 1, "bob"),
        ("speedway", 2, "ana"),
    ]


def test_sorting_by_any_column_keeps_rank_order_for_ties(league: League) -> None:
    record_race(league, race_result("cat", [13.0, 13.0]))
    record_race(league, race_result("Bea", [12.0]))
    record_race(league, race_result("al", [14.0, 14.0, 14.0]))
    rows = leaderboard(league, Filters())
    assert [r.racer for r in sort_rows(rows, "racer")] == ["al", "Bea", "cat"]
    assert [r.racer for r in sort_rows(rows, "laps", reverse=True)] == ["al", "cat", "Bea"]
    assert [r.racer for r in sort_rows(rows, "best", reverse=True)] == ["al", "cat", "Bea"]
    assert [r.racer for r in sort_rows(rows, "rank")] == ["Bea", "cat", "al"]
    with pytest.raises(LeagueError, match="cannot sort by 'speed'"):
        sort_rows(rows, "speed")


def test_the_cached_board_agrees_with_rank_over_every_entry(league: League) -> None:
    """Random races, many ties: the board (SQL) must pick what rank() picks from scratch."""
    rng = random.Random(5)
    results = []
    for i in range(120):
        laps = [rng.choice([11.0, 11.5, 12.0, 12.5]) for _ in range(rng.randint(0, 5))]
        offtracks = [rng.choice([0, 0, 1, 4]) for _ in laps]
        racer = rng.choice(["ana", "bob", "cy", "dee", "Eve"])
        result = race_result(
            racer,
            laps,
            offtracks=offtracks,
            model=f"m{i}",
            started_at=f"2024-05-01T19:{rng.randint(0, 59):02d}:00.000Z",
        )
        results.append(result)
        record_race(league, result)
    for method in RankingMethod:
        best: dict[str, RaceResult] = {}
        for result in rank(_rescored(result, method) for result in results):
            best.setdefault(result.racer, result)
        want = [result.record_id for result in rank(best.values())]
        got = [row.record_id for row in leaderboard(league, Filters(), method)]
        assert got == want, method


def _rescored(result: RaceResult, method: RankingMethod) -> RaceResult:
    rules = replace(result.rules, ranking=method)
    return replace(result, rules=rules, scoring=score_laps(result.laps, rules))


def test_text_formats_keep_names_literal(league: League) -> None:
    record_race(league, race_result("[bold red]x | *y*", [12.0]))
    rows = leaderboard(league, Filters())
    columns = leaderboard_columns(RankingMethod.BEST_LAP, show_track=False, iso_times=True)
    csv_text = to_csv(columns, rows)
    assert csv_text.splitlines()[0] == "rank,racer,model,best lap,average,laps,off-tracks,submitted"
    assert '"[bold red]x | *y*"' in csv_text or "[bold red]x | *y*" in csv_text
    markdown = to_markdown(columns, rows)
    assert markdown_escape("[bold red]x | *y*") in markdown
    assert "\\|" in markdown and "\\*y\\*" in markdown


def test_a_csv_export_never_hands_a_spreadsheet_a_formula(league: League) -> None:
    payload = '=HYPERLINK("http://evil.example","click")'
    record_race(league, race_result(payload, [12.0], model="@SUM(A1)"))
    rows = leaderboard(league, Filters())
    columns = leaderboard_columns(RankingMethod.BEST_LAP, show_track=False, iso_times=True)
    (record,) = csv.DictReader(io.StringIO(to_csv(columns, rows)))
    assert record["racer"] == "'" + payload  # shown as the text it is
    assert record["model"] == "'@SUM(A1)"
    assert record["best lap"] == "12.000"  # numbers stay numbers


def test_a_tracks_leaderboard_is_read_in_order_from_one_index(league: League) -> None:
    # At a million laps sorting a track's board, or looking each row up, is most of the
    # query's time (benchmarks.league.board): the plan must read one covering index in its order.
    sql, params = board_sql(Filters(track_hash="0" * 64), RankingMethod.BEST_LAP)
    plan = " ".join(str(row[3]) for row in league.conn.execute(f"EXPLAIN QUERY PLAN {sql}", params))
    assert "COVERING INDEX board_in_order" in plan
    assert "TEMP B-TREE" not in plan


def test_a_board_read_in_index_order_ranks_exactly_as_rank_does(league: League) -> None:
    # The board path numbers rows in the order SQL returns them, sorting only rows tied up
    # to the racer's name: it must agree with rank() everywhere, ties and casing included.
    from league.leaderboard import _board_rows, board_of, rank_groups

    rng = random.Random(5)
    names = ["ana", "Bob", "bob2", "Émile", "émilie", "zoe", "Zed", "ßigma", "SSam", "al"]
    for i, name in enumerate(names):
        for _ in range(2):
            laps = [rng.choice([11.0, 11.0004, 11.5, 12.0]) for _ in range(3)]
            started = rng.choice(["2024-05-01T19:00:00.000Z", "2024-05-01T19:00:00.001Z"])
            offtracks = [rng.choice([0, 0, 1]) for _ in laps]
            record_race(
                league,
                race_result(name, laps, offtracks=offtracks, started_at=started, seed=i),
            )
    for method in RankingMethod:
        rows = leaderboard(league, Filters(), method)
        fresh = _board_rows(league, Filters(), method)
        order = list(dict.fromkeys(board_of(row) for row in rows))
        expected = rank_groups(fresh, board_of, order)  # rank() over the whole board
        assert [row.record_id for row in rows] == [row.record_id for row in expected]
        assert [row.rank for row in rows] == list(range(1, len(rows) + 1))


def test_boards_ranked_from_runs_match_boards_ranked_by_lookup() -> None:
    """The board query returns rows board after board, and the leaderboard ranks each run
    as it comes (league.leaderboard._ranked_boards); rows of one board in two runs are
    still ranked as one board, in the boards' name order, as the generic path ranks them."""
    from league.leaderboard import LeaderboardRow, _ranked_boards

    def row(racer: str, track: str, score: float, race_type: str = "time_trial") -> LeaderboardRow:
        return LeaderboardRow(
            f"id-{racer}-{track}-{race_type}", "race", racer, racer, "m", f"hash-{track}",
            track, None, score, 0, 3, "2026-01-01T00:00:00Z", score, score, 0, 3,
            "racer-tui/3", race_type,
        )  # fmt: skip

    rows = [
        row("ana", "Zeta", 9.0),
        row("bob", "Zeta", 8.0),
        row("cy", "alpha", 7.5),
        row("dee", "Zeta", 7.0),  # Zeta again, after another board: not one run
        row("eve", "alpha", 6.0, "head_to_bot"),
    ]
    ranked = _ranked_boards(list(rows))
    assert [(r.racer, r.rank) for r in ranked] == [
        ("eve", 1),  # alpha, head to bot: a board of its own
        ("cy", 1),  # alpha, time trial
        ("dee", 1),  # Zeta: one board of three, ranked by score
        ("bob", 2),
        ("ana", 3),
    ]
    in_runs = _ranked_boards([rows[2], rows[4], rows[3], rows[1], rows[0]])
    assert [(r.racer, r.rank) for r in in_runs] == [(r.racer, r.rank) for r in ranked]

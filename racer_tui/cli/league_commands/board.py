"""`racer-tui submit` and `racer-tui leaderboard`: a result into the league, and its boards."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from rich.text import Text

from league.droa_rankings import DroaEntry, droa_laps, droa_rankings, droa_rules_for
from league.errors import LeagueError
from league.leaderboard import (
    Filters,
    LeaderboardRow,
    board_of,
    leaderboard,
    mark_verification,
    method_for,
    mixed_runtimes,
    race_types_on,
    several_boards,
    sort_rows,
)
from league.nights import get_night, list_nights
from league.opening import open_league
from league.race_types import (
    HEAD_TO_HEAD_BOARD,
    TIME_TRIAL,
    board_name,
    option_name,
    parse_race_type,
    words,
)
from league.racers import get_racer
from league.report import SCORE_TITLES, leaderboard_columns, leaderboard_json, to_csv, to_markdown
from league.report import Column as ReportColumn
from league.seasons import get_season
from league.store import League
from league.submissions import submit_model
from league.tracks import track_for
from racer_tui.cli.league_commands.head_to_head_board import show_head_to_head_board
from racer_tui.cli.output import plain_table, print_json, print_table
from sim.race.rules import DEFAULT_RULES, RankingMethod, Verification
from sim.training.drivers import DriversByHash


def run(args: argparse.Namespace) -> int:
    with open_league(args.db) as league:
        if args.command == "submit":
            return submit(league, args)
        return show_leaderboard(league, args)


def submit(league: League, args: argparse.Namespace) -> int:

    submission, outcome = submit_model(
        league,
        args.model,
        args.racer,
        track=args.track,
        evaluation=args.evaluation,
        model_name=args.model_name,
        allow_stale=args.stale_ok,
    )
    best = submission.best_lap
    if args.json:
        print_json(
            {
                "id": outcome.submission_id,
                "duplicate": outcome.duplicate,
                "racer": submission.racer,
                "model": submission.model_name,
                "track": submission.track_name,
                "source": submission.source,
                "race_type": submission.race_type,
                "best_lap": best,
                "laps": len(submission.completed_laps),
                "trials": len(submission.laps),
            }
        )
        return 0
    if outcome.duplicate:
        print(f"Already in the league as {outcome.submission_id}; nothing added.")
        return 0

    lap_text = "no completed lap" if best is None else f"best lap {best:.3f} s"
    # Said when it is not a time trial: its laps go on that race type's board.
    where = board_name(submission.track_name, submission.physics, submission.race_type)
    if submission.race_type == TIME_TRIAL:
        where = submission.track_name
    print(
        f"Submitted {submission.model_name} for {submission.racer} on {where}: "
        f"{lap_text}, {len(submission.completed_laps)} of {len(submission.laps)} trials "
        f"completed (id {outcome.submission_id})."
    )
    return 0


def show_leaderboard(league: League, args: argparse.Namespace) -> int:
    if args.race_type == HEAD_TO_HEAD_BOARD:
        return show_head_to_head_board(league, args, garage_model_hashes())

    night_ids: list[str] | None = None
    if args.night:
        night_ids = [get_night(league, args.night).id]
    if args.season:
        season = get_season(league, args.season)
        season_nights = [night.id for night in list_nights(league) if night.season_id == season.id]
        night_ids = (
            season_nights
            if night_ids is None
            else [night for night in night_ids if night in season_nights]
        )
    track = track_for(league, args.track) if args.track else None
    # A track's board is its time trials' unless --race-type picks another; a night's races
    # are of the night's race type, and a listing of every track shows every board.
    race_type = (
        parse_race_type(args.race_type)
        if args.race_type
        else (TIME_TRIAL if track is not None and night_ids is None else None)
    )
    models_here = garage_model_hashes()
    filters = Filters(
        track_hash=track.track_hash if track is not None else None,
        racer=get_racer(league, args.racer).name if args.racer else None,
        night_ids=night_ids,
        race_type=race_type,
        verification=Verification(args.verification),
        local_models=models_here,
    )
    # A night's races rank by the night's own rules unless --by says otherwise.
    method = (
        method_for(args.by) if args.by else (None if night_ids is not None else method_for("best"))
    )
    rows = leaderboard(league, filters, method)
    said = False
    if not rows and track is not None and race_type is not None:
        said = _other_boards(
            league, track.track_hash, track.name, race_type, args.format == "table"
        )
    rows = sort_rows(rows, args.sort, reverse=args.reverse)
    if args.limit is not None:
        if args.limit < 1:
            raise LeagueError("--limit must be at least 1.")
        rows = rows[: args.limit]
    mark_verification(league, rows, models_here)
    shown_method = method if method is not None else _night_method(league, night_ids)
    show_track = several_boards(rows)
    if args.format == "droa":
        print_json(_droa_document(league, rows, method, night_ids))
        return 0
    if args.format == "json":
        print_json(leaderboard_json(rows, shown_method))
        return 0
    columns = leaderboard_columns(
        shown_method, show_track=show_track, iso_times=args.format == "csv", verification=True
    )
    if args.format == "csv":
        sys.stdout.write(to_csv(columns, rows))
    elif args.format == "markdown":
        sys.stdout.write(to_markdown(columns, rows))
    else:
        # One table per board: a track under one race type and one physics, ranked alone.
        boards: dict[tuple[str, str, str], list[LeaderboardRow]] = {}
        for row in rows:
            boards.setdefault(board_of(row), []).append(row)
        if not rows:
            if not said:
                print(_no_laps(track.name if track is not None else None, race_type))
            return 0
        single = len(boards) == 1 or args.sort != "rank"
        groups = [rows] if single else list(boards.values())
        for group in groups:
            _print_board(group, columns if single else _without_track(columns), shown_method)
            note = mixed_runtimes(group)
            if note is not None:
                print(note)
    return 0


def _no_laps(track_name: str | None, race_type: str | None) -> str:
    """What an empty table says, and how laps get there."""

    kind = "" if race_type is None else f"{words(race_type).replace(' ', '-')} "
    where = f" on {track_name}" if track_name is not None else " in this league"
    return (
        f"No {kind}laps{where} yet: record a race with racer-tui --race MODEL --record, "
        "or submit an evaluation with racer-tui submit."
    )


def _other_boards(
    league: League, track_hash: str, track_name: str, race_type: str, on_stdout: bool
) -> bool:
    """Say which race types a track has laps of, when the board asked for has none (on
    stderr beside JSON, CSV or Markdown, which stay the data alone); False when it has
    none at all."""

    others = [kind for kind in race_types_on(league, track_hash) if kind != race_type]
    if not others:
        return False
    options = " or ".join(f"--race-type {option_name(kind)}" for kind in others)
    print(
        f"No {words(race_type).replace(' ', '-')} laps on {track_name} yet; its other "
        f"board{'s' if len(others) > 1 else ''}: {options}.",
        file=sys.stdout if on_stdout else sys.stderr,
    )
    return True


def _print_board(
    rows: Sequence[LeaderboardRow], columns: Sequence[ReportColumn], method: RankingMethod
) -> None:

    tracks = sorted({row.track_name for row in rows})
    where = f"{tracks[0]}, " if len(tracks) == 1 else ""
    table = plain_table(f"Leaderboard: {where}ranked by {SCORE_TITLES[method]}")
    for column in columns:
        # Names get room first; on a narrow terminal the headers of numbers wrap.
        named = column.title in ("racer", "model", "track")
        table.add_column(
            column.title,
            justify="right" if column.numeric else "left",
            min_width=8 if named else None,
        )
    for row in rows:
        table.add_row(*(Text(column.cell(row)) for column in columns))
    print_table(table)


def _without_track(columns: Sequence[ReportColumn]) -> list[ReportColumn]:
    return [column for column in columns if column.title != "track"]


def _droa_document(
    league: League,
    rows: Sequence[LeaderboardRow],
    method: RankingMethod | None,
    night_ids: Sequence[str] | None,
) -> dict[str, Any]:
    """Each board's rankings as DeepRacer on AWS would publish them: its timing method and
    minimumLaps from the rules (a night's own, or --by's with 3 laps), its stats computed
    from each racer's laps as it computes them from its metrics."""
    rules = (
        get_night(league, night_ids[0]).rules
        if method is None and night_ids
        else replace(DEFAULT_RULES, ranking=method or DEFAULT_RULES.ranking)
    )
    timing, minimum = droa_rules_for(rules)
    boards: dict[tuple[str, str, str], list[LeaderboardRow]] = {}
    for row in rows:
        boards.setdefault(board_of(row), []).append(row)
    leaderboards = []
    for group in boards.values():
        entries = [
            DroaEntry(row.display_name, row.model, droa_laps(league, row.record_id, row.kind))
            for row in group
        ]
        leaderboards.append(
            {
                "track": group[0].track_name,
                "raceType": group[0].race_type.upper(),
                "timingMethod": timing.value,
                "minimumLaps": minimum,
                "rankings": droa_rankings(entries, timing, minimum),
            }
        )
    return {"leaderboards": leaderboards}


def _night_method(league: League, night_ids: Sequence[str] | None) -> RankingMethod:

    if night_ids:
        return get_night(league, night_ids[0]).rules.ranking
    return DEFAULT_RULES.ranking


def garage_model_hashes() -> frozenset[str]:
    """The garage's model hashes: their results are verifiable here."""

    return DriversByHash().models_here()

"""`racer-tui --race MODEL [MODEL ...] --track TRACK`: headless time trials for scripts.

`--race` is a top-level mode, not a subcommand: `racer_tui.cli.main.main` hands the whole
command line to `main` here, which has its own parser. Each model races once under the
rules, one after the other; the output is a table per race and the standings, or with
`--json` one JSON document and nothing else on stdout.

Exit codes: 0 success, 2 bad arguments or input (unknown model or track, bad rules, a
damaged bundle), 1 an unexpected failure. Messages go to stderr as one sentence.

This path never imports textual, and imports torch only when a trained model races.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

from league.errors import LeagueError
from league.ranking import rank
from racer_tui.cli.head_to_head_output import (
    head_to_head_document,
    head_to_head_summary,
    head_to_head_table,
    incident_lines,
)
from racer_tui.cli.output import print_json
from racer_tui.cli.rules_option import RACE_HELP as RULES_HELP
from racer_tui.cli.rules_option import RACE_PRESETS, rules_option
from sim.foundation.plain_names import MAX_NAME_LENGTH, is_plain_name
from sim.foundation.plural import counted
from sim.foundation.remedies import RemedyError, echoed
from sim.garage.imported import BUNDLE_SUFFIX
from sim.physics.objects.settings import RaceType
from sim.race.driver import Driver
from sim.race.engine import run_race
from sim.race.head_to_head import MAX_CARS, MIN_CARS, Entry, HeadToHeadResult, run_head_to_head
from sim.race.result import RaceResult
from sim.race.rules import RaceRules, RankingMethod, RulesError, rules_from_mapping
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track
from sim.tracks.track import Track
from sim.training.drivers import RaceSetupError, resolve_driver

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USER_ERROR = 2


@dataclass(frozen=True)
class Entrant:
    spec: str  # what was typed: reference, a model name, a bundle file
    racer: str
    driver: Driver


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="racer-tui --race",
        description=(
            "Race models in 4-minute time trials under league rules (or the race type "
            "the rules choose: object avoidance, head-to-bot), without the app. "
            "MODEL is `reference` (the no-learning reference driver), a garage model name, "
            f"or a {BUNDLE_SUFFIX} file. Several models race one after the other and are ranked."
        ),
    )
    parser.add_argument("--race", nargs="+", required=True, metavar="MODEL", dest="models")
    parser.add_argument(
        "--track",
        default=DEFAULT_TRACK,
        help=f"track name (world or console name) or .npy file (default: {DEFAULT_TRACK}, "
        "re:Invent 2018)",
    )
    parser.add_argument(
        "--racer", help="the racer's name in the results (default: each model's name)"
    )
    parser.add_argument("--rules", metavar="FILE|PRESET", help=RULES_HELP)
    parser.add_argument("--window", type=float, metavar="SECONDS", help="race window")
    parser.add_argument("--penalty", type=float, metavar="SECONDS", help="off-track penalty")
    parser.add_argument(
        "--max-offtracks",
        metavar="N",
        help="off-tracks a lap may have and still count, or 'unlimited'",
    )
    parser.add_argument(
        "--ranking",
        choices=[method.value for method in RankingMethod],
        help="rank by the best lap, the best average of N consecutive laps, or N laps' total",
    )
    parser.add_argument("--ranking-laps", type=int, metavar="N", help="N for the ranking")
    parser.add_argument(
        "--laps",
        type=int,
        metavar="N",
        help="a lap-count race: it ends after N laps, or when the window closes first",
    )
    parser.add_argument("--seed", type=int, default=0, help="recorded with each result")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--record", action="store_true", help="store results in the league")
    parser.add_argument("--db", type=Path, metavar="FILE", help="the league database for --record")
    parser.add_argument(
        "--trace-dir", type=Path, help="write each race's sim-trace CSV into this folder"
    )
    return parser


def main(argv: Sequence[str]) -> int:
    """Run `racer-tui --race ...`; returns the exit code."""
    arguments = list(argv)
    parser = build_parser()
    if "-h" in arguments or "--help" in arguments:
        parser.print_help()
        return EXIT_OK
    try:
        args = parser.parse_args(arguments)
    except SystemExit as exit_:  # argparse has printed its usage message to stderr
        return int(exit_.code) if isinstance(exit_.code, int) else EXIT_USER_ERROR
    try:
        return _run(args)
    except RemedyError as error:
        print(f"racer-tui: {error}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        return 130
    except Exception as error:  # the one place that reports the unexpected
        print(
            f"racer-tui: the race failed unexpectedly ({type(error).__name__}: {error}); "
            "please report this with the command you ran.",
            file=sys.stderr,
        )
        return EXIT_FAILURE


def _run(args: argparse.Namespace) -> int:
    rules = race_rules(args)
    if args.seed < 0:
        raise RaceSetupError(f"--seed must be a whole number of at least 0, not {args.seed}.")
    track = resolve_track(args.track)
    if rules.race_type is RaceType.HEAD_TO_MODEL:
        return _run_head_to_head(args, rules, track)
    racer = _racer_name(args.racer) if args.racer is not None else None
    # Every entrant is checked before the first race starts: a typo fails fast.
    entrants = [
        Entrant(spec, racer or driver.name, driver)
        for spec in args.models
        for driver in [resolve_driver(spec, track)]
    ]
    keep_trace = bool(args.record or args.trace_dir)
    console = Console()
    results: list[RaceResult] = []
    trace_files: dict[str, Path] = {}
    for entrant in entrants:
        result = run_race(
            track, rules, entrant.driver, racer=entrant.racer, seed=args.seed, keep_trace=keep_trace
        )
        results.append(result)
        if args.trace_dir is not None:
            trace_files[result.result_id] = _write_trace(result, args.trace_dir)
        if not args.json:
            console.print(race_table(result, track))
            console.print(Text(race_summary(result)))
    recorded = _record(results, args.db) if args.record else []

    standings = rank(results)
    if args.json:
        print_json(
            race_document(
                track,
                rules,
                results,
                standings=standings,
                trace_files=trace_files,
                recorded=recorded,
            )
        )
        return EXIT_OK
    if len(results) > 1:
        console.print(standings_table(standings))
    for path in trace_files.values():
        console.print(Text(f"trace: {path}"))
    if recorded:
        console.print(Text(f"recorded {counted(len(recorded), 'race')} in the league."))
    return EXIT_OK


def _run_head_to_head(args: argparse.Namespace, rules: RaceRules, track: Track) -> int:
    """The models on the track together (sim.race.head_to_head), one race."""
    if not MIN_CARS <= len(args.models) <= MAX_CARS:
        raise RaceSetupError(
            f"a head-to-head race takes {MIN_CARS} to {MAX_CARS} models, not "
            f"{len(args.models)}; name them after --race, the first on the front of the grid."
        )
    if args.racer is not None:
        raise RaceSetupError(
            "--racer: each car of a head-to-head race is its model's; race without it."
        )
    # A model named twice is one driver: it acts for both its cars in one batch.
    drivers: dict[str, Driver] = {}
    for spec in args.models:
        if spec not in drivers:
            drivers[spec] = resolve_driver(spec, track)
    entries = [Entry(drivers[spec].name, drivers[spec]) for spec in args.models]
    keep_trace = args.trace_dir is not None
    result = run_head_to_head(track, rules, entries, seed=args.seed, keep_trace=keep_trace)
    # A sim-trace CSV for each car, as simapp writes one for each agent.
    trace_files = {
        finish.car: _write_trace(finish.result, args.trace_dir)
        for finish in result.cars
        if args.trace_dir is not None
    }
    recorded = _record_head_to_head(result, args.db) if args.record else None
    if args.json:
        document = head_to_head_document(result, track, trace_files)
        print_json({**document, "recorded": [recorded] if recorded else []})
        return EXIT_OK
    console = Console()
    console.print(head_to_head_table(result, track))
    for line in incident_lines(result):
        console.print(Text(line))
    console.print(Text(head_to_head_summary(result)))
    for finish in result.cars:
        if finish.car in trace_files:
            console.print(Text(f"trace of car {finish.car + 1}: {trace_files[finish.car]}"))
    if recorded:
        console.print(Text("recorded the head-to-head race in the league."))
    return EXIT_OK


def _record_head_to_head(result: HeadToHeadResult, db_path: Path | None) -> str:
    from league.head_to_heads import record_head_to_head  # noqa: PLC0415 (only for --record)
    from league.opening import open_league  # noqa: PLC0415 (only for --record)

    try:
        with open_league(db_path) as league:
            return record_head_to_head(league, result)
    except LeagueError as error:
        raise RaceSetupError(f"cannot record the race: {error}") from None


# --- rules and entrants -----------------------------------------------------------------------


def race_rules(args: argparse.Namespace) -> RaceRules:
    """The rules file (or the defaults), then each command-line override, validated."""
    rules = rules_option(args.rules, RACE_PRESETS) if args.rules is not None else RaceRules()
    overrides: list[tuple[str, str, object]] = [
        ("--window", "window_seconds", args.window),
        ("--penalty", "penalty_seconds", args.penalty),
        ("--max-offtracks", "max_offtracks_per_lap", _offtrack_limit(args.max_offtracks)),
        ("--ranking", "ranking", args.ranking),
        ("--ranking-laps", "ranking_laps", args.ranking_laps),
        ("--laps", "lap_count", args.laps),
    ]
    given = [(flag, key, value) for flag, key, value in overrides if value is not None]
    for flag, key, value in given:  # each value on its own first, so its flag is named
        try:
            rules_from_mapping({key: value}, base=RaceRules())
        except RulesError as error:
            raise RulesError(f"{flag}: {error}") from None
    # Then together: `--laps 2 --ranking-laps 2` must not fail on the file's ranking_laps.
    try:
        return rules_from_mapping({key: value for _, key, value in given}, base=rules)
    except RulesError as error:
        text = str(error)
        for flag, key, _ in overrides:  # what the racer typed, not the file's keys
            text = re.sub(rf"\b{key}\b", f"{flag} ({key})", text)
        raise RulesError(text) from None


def _offtrack_limit(text: str | None) -> int | str | None:
    if text is None:
        return None
    if text.strip().lower() == "unlimited":
        return "unlimited"
    try:
        return int(text)
    except ValueError:
        raise RaceSetupError(
            f"--max-offtracks must be a whole number or 'unlimited', not {text!r}."
        ) from None


def _racer_name(text: str) -> str:
    name = text.strip()
    if not is_plain_name(name):
        raise RaceSetupError(
            f"{echoed(text)} cannot be a racer name: use 1 to {MAX_NAME_LENGTH} printable "
            "characters (no line breaks or control characters)."
        )
    return name


# --- outputs ------------------------------------------------------------------------------------


def _write_trace(result: RaceResult, folder: Path) -> Path:
    if result.trace is None:  # pragma: no cover - traces are kept whenever --trace-dir is set
        raise RaceSetupError("the race kept no trace to write.")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{result.result_id}.csv"
        result.trace.write_csv(path)
    except OSError as error:
        raise RaceSetupError(
            f"cannot write the trace into {folder}: {error.strerror or error}; "
            "choose a folder you can write to."
        ) from None
    return path


def _record(results: Sequence[RaceResult], db_path: Path | None) -> list[str]:
    try:
        from league.opening import open_league  # noqa: PLC0415 (the league's SQLite: only for --record)
        from league.races import record_race  # noqa: PLC0415 (the league's SQLite: only for --record)
    except ImportError:  # pragma: no cover - the league ships with racer-tui
        raise RaceSetupError(
            "--record is not available: this racer-tui has no league database yet."
        ) from None
    try:
        with open_league(db_path) as league:
            return [record_race(league, result) for result in results]
    except LeagueError as error:
        raise RaceSetupError(f"cannot record the races: {error}") from None


def _best_lap_seconds(result: RaceResult) -> float | None:
    best = result.best_lap
    return None if best is None else best.time_seconds


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def race_table(result: RaceResult, track: Track) -> Table:
    """One race's laps. Names are user text: Text() keeps them literal, never markup."""
    rules = result.rules
    among = "" if rules.race_type is RaceType.TIME_TRIAL else f", {rules.race_words}"
    title = Text(f"{result.racer} ({result.model_name}) on {track.name}{among}")
    table = Table(title=title, title_justify="left")
    # Crashes only where there is something to crash into.
    crashes = rules.race_type is not RaceType.TIME_TRIAL
    # Turned round only when it happened: it explains a penalty without an off-track.
    reversals = any(lap.reversals for lap in result.laps)
    shown = {"crashes": crashes, "turned round": reversals}
    names = ("lap", "time s", "raw s", "penalty s", "off-tracks", "crashes", "turned round")
    for name in (*names, "counts"):
        if shown.get(name, True):
            table.add_column(name, justify="right" if name != "counts" else "center")
    scoring = set(result.scoring.lap_numbers)
    for lap in result.laps:
        cells = [
            f"{lap.number}{' *' if lap.number in scoring else ''}",
            f"{lap.time_seconds:.3f}",
            f"{lap.raw_seconds:.3f}",
            f"{lap.penalty_seconds:g}",
            str(lap.offtracks),
        ]
        if crashes:
            cells.append(str(lap.crashes))
        if reversals:
            cells.append(str(lap.reversals))
        table.add_row(*cells, "yes" if lap.valid else "no")
    return table


def race_summary(result: RaceResult) -> str:
    best = result.best_lap
    laps = len(result.laps)
    crashes = sum(lap.crashes for lap in result.laps)
    crashed = f", {counted(crashes, 'crash', 'crashes')}" if crashes else ""
    return (
        f"{laps} lap{'s' if laps != 1 else ''}, {result.valid_laps} counting, "
        f"{result.total_offtracks} off-track{'s' if result.total_offtracks != 1 else ''}"
        f"{crashed}; "
        f"best lap {_seconds(None if best is None else best.time_seconds)} s; "
        f"score {_seconds(result.score)} ({result.rules.describe()})."
    )


def standings_table(standings: Sequence[RaceResult]) -> Table:
    table = Table(title="Standings", title_justify="left")
    for name in ("pos", "racer", "model", "score s", "off-tracks", "counting laps", "best lap s"):
        table.add_column(name, justify="left" if name in ("racer", "model") else "right")
    for position, result in enumerate(standings, start=1):
        best = result.best_lap
        table.add_row(
            str(position),
            Text(result.racer),
            Text(result.model_name),
            _seconds(result.score),
            str(result.scoring_offtracks),
            str(result.valid_laps),
            _seconds(None if best is None else best.time_seconds),
        )
    return table


def race_document(
    track: Track,
    rules: RaceRules,
    results: Sequence[RaceResult],
    *,
    standings: Sequence[RaceResult],
    trace_files: dict[str, Path],
    recorded: Sequence[str],
) -> dict[str, Any]:
    """The `--json` document: every race in running order, then the standings."""
    races = []
    for result in results:
        entry = result.to_json()
        if result.result_id in trace_files:
            entry["trace_file"] = str(trace_files[result.result_id])
        races.append(entry)
    return {
        "track": {"name": track.name, "hash": track.content_hash, "length_m": track.length},
        "rules": rules.to_dict(),
        "races": races,
        "standings": [
            {
                "position": position,
                "result_id": result.result_id,
                "racer": result.racer,
                "model_name": result.model_name,
                "score": result.score,
                "scoring_offtracks": result.scoring_offtracks,
                "valid_laps": result.valid_laps,
                "best_lap_seconds": None
                if result.best_lap is None
                else result.best_lap.time_seconds,
            }
            for position, result in enumerate(standings, start=1)
        ],
        "recorded": list(recorded),
    }

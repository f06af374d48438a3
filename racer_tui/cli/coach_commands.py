"""`racer-tui coach MODEL`: where a model's lap loses time against the limit lap, sector by
sector (`sim.coach`)."""

from __future__ import annotations

import argparse
from typing import Any

from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from sim.coach.lap_analysis import coach_sentence
from sim.garage.coach_session import coach_model
from sim.garage.folder import open_model

NAMES = ("coach",)


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    coach = commands.add_parser(
        "coach",
        help="where a model's evaluated lap loses time against the limit lap, by sector",
    )
    coach.add_argument("model", help="garage model name or model folder path")
    coach.add_argument(
        "--lap",
        default="best",
        metavar="best|N",
        help="the latest evaluation's fastest lap (default) or trial N",
    )
    coach.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:

    coaching = coach_model(open_model(args.model), args.lap)
    report = coaching.report
    ranked = report.ranked()
    if args.json:
        print_json(
            {
                "model": args.model,
                "track": coaching.track.name,
                "lap": report.label,
                "lap_s": round(report.seconds, 3),
                "limit_lap_s": round(report.limit_seconds, 3),
                "flying_limit_s": round(report.flying_limit, 3),
                "car_flying_limit_s": round(coaching.car_limit.flying_seconds, 3),
                "gap_to_flying_limit_percent": round(report.gap_percent, 1),
                "from_rest": report.from_rest,
                "notes": report.notes(),
                "sectors": [_sector_json(item, coach_sentence(item)) for item in ranked],
            }
        )
        return 0
    title = Text(
        f"{args.model} on {coaching.track.name}, {report.label}: {report.seconds:.3f} s, "
        f"{report.gap_words} ({report.flying_limit:.3f} s "
        f"within its actions; {coaching.car_limit.flying_seconds:.3f} s with any)"
    )
    table = Table(title=title, title_justify="left")
    table.add_column("sector")
    table.add_column("lost", justify="right")
    table.add_column("time", justify="right")
    table.add_column("limit", justify="right")
    table.add_column("what the car does", ratio=1)
    for item in ranked:
        sentence = coach_sentence(item).split(": ", 1)[1]
        table.add_row(
            item.sector.name,
            item.lost_text,
            f"{item.seconds:.2f}",
            f"{item.limit_seconds:.2f}",
            Text(sentence),
        )
    print_table(table)
    for note in report.notes():
        print(note)
    return 0


def _sector_json(item: Any, sentence: str) -> dict[str, Any]:
    sector = item.sector
    return {
        "sector": sector.name,
        "corner": sector.corner,
        "from_m": round(sector.start, 2),
        "to_m": round(sector.end, 2),
        "seconds": round(item.seconds, 3),
        "limit_seconds": round(item.limit_seconds, 3),
        "lost_s": round(item.lost, 3),
        "off_line_m": round(item.off_line, 3),
        "speed_gap_m_s": round(item.speed_gap, 2),
        "slowest_point_gap_m_s": round(item.apex_gap, 2),
        "braking_gap_m": round(item.braking_gap, 2),
        "sentence": sentence,
    }

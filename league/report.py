"""Leaderboard and standings as plain data and text (JSON, CSV, Markdown).

Front ends draw tables from the same `Cell` lists. Racer names and other user text stay
literal: CSV quotes them, Markdown escapes its own syntax characters, and rich front ends
put them in `Text` cells, so a racer called `[bold]x` or `**x**` shows exactly that.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from league.leaderboard import LeaderboardRow
from sim.race.rules import RankingMethod

SCORE_TITLES = {
    RankingMethod.BEST_LAP: "best lap",
    RankingMethod.BEST_AVERAGE: "best average",
    RankingMethod.TOTAL_TIME: "total time",
}


@dataclass(frozen=True)
class Column:
    title: str
    cell: Callable[[Any], str]
    numeric: bool = False


def seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def when(iso: str) -> str:
    """'2024-05-01T19:02:03.456Z' -> '2024-05-01' (UTC); CSV and JSON keep the full time."""
    return iso[:10]


def leaderboard_columns(
    method: RankingMethod, *, show_track: bool, iso_times: bool = False, verification: bool = False
) -> list[Column]:
    """The columns of a leaderboard; `verification` adds each row's standing here
    (replayed, verifiable, unverifiable: league.trust.standing), once it is worked out."""
    columns = [
        Column("rank", lambda row: str(row.rank), numeric=True),
        Column("racer", lambda row: row.display_name),
        Column("model", lambda row: row.model),
    ]
    if show_track:
        columns.append(Column("track", lambda row: row.track_name))
    if method is not RankingMethod.BEST_LAP:
        columns.append(Column(SCORE_TITLES[method], lambda row: seconds(row.score), True))
    columns += [
        Column("best lap", lambda row: seconds(row.best_lap), numeric=True),
        Column("average", lambda row: seconds(row.average_lap), numeric=True),
        Column("laps", lambda row: str(row.valid_laps), numeric=True),
        Column("off-tracks", lambda row: str(row.offtracks), numeric=True),
        Column(
            "submitted",
            (lambda row: row.recorded_at) if iso_times else (lambda row: when(row.recorded_at)),
        ),
    ]
    if verification:
        columns.append(Column("verification", lambda row: row.verification or "-"))
    return columns


def leaderboard_json(rows: Sequence[LeaderboardRow], method: RankingMethod) -> list[dict[str, Any]]:
    return [
        {
            "rank": row.rank,
            "racer": row.display_name,
            "racer_name": row.racer,
            "model": row.model,
            "track": row.track_name,
            "track_hash": row.track_hash,
            "physics": row.physics,
            "race_type": row.race_type,
            "ranking": method.value,
            "score": row.score,
            "best_lap": row.best_lap,
            "average": row.average_lap,
            "laps": row.valid_laps,
            "laps_driven": row.laps_driven,
            "offtracks": row.offtracks,
            "submitted": row.recorded_at,
            "kind": row.kind,
            "id": row.record_id,
            "night_id": row.night_id,
            # replayed, verifiable or unverifiable here (league.trust.standing); None when
            # the front end did not work it out.
            "verification": row.verification or None,
            # The policy runtime that drove a race (sim.training.runtimes); None for the
            # rest, or when the front end did not work it out.
            "runtime": row.runtime or None,
        }
        for row in rows
    ]


def cells(columns: Sequence[Column], rows: Sequence[Any]) -> list[list[str]]:
    return [[column.cell(row) for column in columns] for row in rows]


# What a spreadsheet reads as the start of a formula in a cell: `=HYPERLINK(...)` in a
# racer's name must stay text when a host opens the export.
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_safe(text: str) -> str:
    """A text cell a spreadsheet shows as text, never runs: a leading apostrophe (which
    spreadsheets hide) before anything that would start a formula."""
    return "'" + text if text.startswith(_FORMULA_START) else text


def to_csv(columns: Sequence[Column], rows: Sequence[Any]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([column.title for column in columns])
    for row in cells(columns, rows):
        writer.writerow(
            [
                cell if column.numeric else spreadsheet_safe(cell)
                for column, cell in zip(columns, row, strict=True)
            ]
        )
    return out.getvalue()


# Characters that start Markdown syntax anywhere in a table cell (CommonMark escapes them).
_MARKDOWN_SPECIAL = re.compile(r"([\\`*_\[\]<>|~&])")


def markdown_escape(text: str) -> str:
    """Text that Markdown shows literally (inside a table cell too)."""
    return _MARKDOWN_SPECIAL.sub(r"\\\1", text)


def to_markdown(columns: Sequence[Column], rows: Sequence[Any]) -> str:
    header = "| " + " | ".join(column.title for column in columns) + " |"
    rule = "| " + " | ".join("---:" if column.numeric else "---" for column in columns) + " |"
    lines = [header, rule]
    for row in cells(columns, rows):
        escaped = [
            cell if column.numeric else markdown_escape(cell)
            for column, cell in zip(columns, row, strict=True)
        ]
        lines.append("| " + " | ".join(escaped) + " |")
    return "\n".join(lines) + "\n"

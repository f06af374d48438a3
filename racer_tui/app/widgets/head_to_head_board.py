"""The League screen's head-to-head board: its table, the highlighted racer's detail and
its export, all from one read of the league (league.head_to_head_board), so the screen,
its files and `racer-tui leaderboard --race-type head-to-head` say the same.

The table has the command line's columns. In a narrow terminal the cars a racer raced give
way first (the detail names them all), then the end of long names (never so much that one
reads as another's), then how many starts were replayed (the detail says it per race), then
the cars finished behind and ahead of; rank, wins and losses always stay.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import replace

from rich.cells import cell_len
from rich.text import Text

from league.board_place import ordinal
from league.head_to_head_board import (
    HEAD_TO_HEAD_COLUMNS,
    HeadToHeadBoard,
    HeadToHeadRow,
    head_to_head_json,
    races_of,
    rival_records,
)
from league.head_to_heads import RecordedHeadToHead
from league.report import to_csv, to_markdown
from league.trust.standing import ResultStanding
from racer_tui.app.widgets.table_fill import Col
from sim.foundation.plural import counted

GIVE_WAY: dict[str, Col] = {
    "car": Col("", keep=1, shrink_to=8, keeps_tail=True),
    "racer": Col("", keep=2, shrink_to=10, collapses=False, stays_distinct=True),
    "replayed": Col("", keep=3),
    "behind": Col("", keep=4),
    "ahead of": Col("", keep=5),
}

EMPTY = (
    "No head-to-head races here yet. Race models together with racer-tui --race A B "
    "--rules head-to-head --record, or race a bracket night's matches (n)."
)


def board_table(board: HeadToHeadBoard) -> tuple[list[Col], list[list[Text]]]:
    """The table's columns (each with how it gives way) and cells, in rank order."""
    columns = [
        replace(GIVE_WAY.get(column.title, Col("")), label=column.title)
        for column in HEAD_TO_HEAD_COLUMNS
    ]
    cells = [
        [
            Text(column.cell(row), justify="right" if column.numeric else "left")
            for column in HEAD_TO_HEAD_COLUMNS
        ]
        for row in board.rows
    ]
    return columns, cells


def export_text(board: HeadToHeadBoard, track_name: str | None, kind: str) -> str:
    """The board as a file: the command line's JSON document, or its columns as CSV or
    Markdown."""
    if kind == "json":
        return json.dumps(head_to_head_json(board, track_name), indent=2) + "\n"
    if kind == "csv":
        return to_csv(HEAD_TO_HEAD_COLUMNS, board.rows)
    return to_markdown(HEAD_TO_HEAD_COLUMNS, board.rows)


def describe_racer(
    board: HeadToHeadBoard,
    row: HeadToHeadRow,
    track_names: Mapping[str, str],
    night_names: Mapping[str, str],
) -> Text:
    """The detail of one racer's row: their record, against each rival, and their races
    (newest first). Names are other machines' text: plain, never markup."""
    text = Text()
    text.append(row.racer, style="bold")
    text.append(f"  {ordinal(row.rank)} of {len(board.rows)}\n")
    text.append(
        f"{counted(row.wins, 'win')}, {counted(row.losses, 'loss', 'losses')} in "
        f"{counted(row.starts, 'start')} · ahead of {counted(row.beaten, 'car')}, "
        f"behind {row.beaten_by}\n",
        style="dim",
    )
    text.append(_replayed_line(row) + "\n", style="dim")
    text.append("cars: ", style="dim")
    text.append(", ".join(row.cars) + "\n")

    text.append("\nAgainst each rival\n", style="bold")
    records = rival_records(board, row.racer)
    if not records:
        text.append("  none yet: they have raced only their own cars\n", style="dim")
    width = max((cell_len(record.rival) for record in records), default=0)
    for record in records:
        text.append("  ")
        text.append(record.rival + " " * (width - cell_len(record.rival)))
        text.append(
            f"  {counted(record.wins, 'win')}, {counted(record.losses, 'loss', 'losses')}\n"
        )

    races = races_of(board, row.racer)
    text.append(f"\nRaces ({len(races)}, newest first)\n", style="bold")
    for race in reversed(races):
        where = _where(race, track_names, night_names)
        text.append_text(_race_lines(race, row.racer, board.standings.get(race.id), where))
    return text


def _where(
    race: RecordedHeadToHead, track_names: Mapping[str, str], night_names: Mapping[str, str]
) -> str:
    """ "beginner-oval · Friday W1-1": its track, and its night's bracket match if any."""
    where = track_names.get(race.track_hash, race.track_hash[:12])
    if race.night_id is not None:
        where += f" · {night_names.get(race.night_id, 'a night')}"
        if race.match_id is not None:
            where += f" {race.match_id}"
    return where


def _race_lines(
    race: RecordedHeadToHead, racer: str, standing: ResultStanding | None, where: str
) -> Text:
    """Two or three lines of one race: when and where, their places and cars and who they
    finished ahead of and behind, and what this machine can vouch for."""
    mine = [place for place in race.places if place.racer == racer]
    text = Text(f"  {race.started_at[:16].replace('T', ' ')} · {where}\n    ")
    text.append(" and ".join(ordinal(place.position) for place in mine))
    text.append(f" of {len(race.places)} (")
    text.append(", ".join(dict.fromkeys(place.model_name for place in mine)) + ")")
    best = mine[0].position  # their better car's, as their record against a rival counts
    rivals = [place for place in race.places if place.racer != racer]
    for words, names in (
        (" · ahead of ", [place.racer for place in rivals if place.position > best]),
        (" · behind ", [place.racer for place in rivals if place.position < best]),
    ):
        if names:
            text.append(words + ", ".join(dict.fromkeys(names)))
    if standing is not None:
        text.append(f"\n    {standing.standing}: {standing.why}", style="dim")
    text.append("\n")
    return text


def _replayed_line(row: HeadToHeadRow) -> str:
    """ "2 of 3 starts replayed here", with the physical starts named apart: a car timed by
    hand on a real track has no model to replay."""
    hand = row.hand_timed_starts
    if not row.replayable_starts:
        return f"{counted(hand, 'start')} hand-timed (physical cars are not replayed)"
    line = f"{row.replayed_starts} of {counted(row.replayable_starts, 'start')} replayed here"
    return line + (f", {hand} hand-timed" if hand else "")

"""What `racer-tui --race A B --rules head-to-head` prints: the finishing order with each
car's laps, crashes, off-tracks and gap to the winner, what happened on the way, and the
same as one JSON document with `--json`."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rich.table import Table
from rich.text import Text

from racer_tui.text.clocks import clock_text
from racer_tui.text.head_to_head import car_name, incident_sentence
from sim.race.head_to_head import CarFinish, HeadToHeadResult
from sim.tracks.track import Track


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def _name(finish: CarFinish) -> str:
    return car_name(finish.result.racer, finish.result.model_name)


def _crashes(finish: CarFinish) -> int:
    return sum(lap.crashes for lap in finish.result.laps)


def _end(finish: CarFinish, result: HeadToHeadResult) -> str:
    """The winner's time, or how far behind it each other car ended."""
    if finish.position == 1:
        return _seconds(finish.finished_at if finish.finished_at is not None else result.clock)
    if finish.gap_seconds is None:
        return "-"
    return f"+{finish.gap_seconds:.3f}"


def head_to_head_table(result: HeadToHeadResult, track: Track) -> Table:
    """The finishing order. Names are user text: Text() keeps them literal, never markup."""
    laps = result.rules.lap_count
    length = f"{laps} laps" if laps is not None else "the whole window"
    title = Text(f"Head-to-head on {track.name}, {length}")
    table = Table(title=title, title_justify="left")
    for name in ("pos", "car", "grid", "laps", "best s", "time s", "crashes", "off-tracks"):
        table.add_column(name, justify="left" if name == "car" else "right")
    for finish in result.cars:
        best = finish.result.best_lap
        table.add_row(
            str(finish.position),
            Text(_name(finish)),
            str(finish.car + 1),
            str(finish.laps_completed),
            _seconds(None if best is None else best.time_seconds),
            _end(finish, result),
            str(_crashes(finish)),
            str(finish.result.total_offtracks),
        )
    return table


def incident_lines(result: HeadToHeadResult) -> list[str]:
    """Crashes and overtakes, in race order, as a commentator would say them."""
    names = {finish.car: f"#{finish.car + 1} {_name(finish)}" for finish in result.cars}
    return [
        f"{clock_text(incident.clock)}  {incident_sentence(incident, names)}"
        for incident in result.incidents
    ]


def head_to_head_summary(result: HeadToHeadResult) -> str:
    winner = result.winner
    crashes = sum(1 for incident in result.incidents if incident.kind == "crash")
    overtakes = len(result.incidents) - crashes
    return (
        f"{_name(winner)} won ({result.rules.describe()}). "
        f"{crashes} crash{'es' if crashes != 1 else ''}, "
        f"{overtakes} overtake{'s' if overtakes != 1 else ''}; time s is the winner's, the "
        "others' how far behind they ended."
    )


def head_to_head_document(
    result: HeadToHeadResult, track: Track, trace_files: Mapping[int, Path] | None = None
) -> dict[str, Any]:
    """The `--json` document of a head-to-head race (`trace_files`: by grid index)."""
    traces = trace_files or {}
    return {
        "race": "head-to-head",
        "race_id": result.race_id,
        "track": {"name": track.name, "hash": track.content_hash, "length_m": track.length},
        "rules": result.rules.to_dict(),
        "seed": result.seed,
        "started_at": result.started_at,
        "clock_seconds": result.clock,
        "cars": [
            {
                "position": finish.position,
                "grid": finish.car + 1,
                "racer": finish.result.racer,
                "model_name": finish.result.model_name,
                "model_hash": finish.result.model_hash,
                "finished_at_seconds": finish.finished_at,
                "laps_completed": finish.laps_completed,
                "distance_m": round(finish.distance, 3),
                "gap_seconds": finish.gap_seconds,
                "best_lap_seconds": None
                if finish.result.best_lap is None
                else finish.result.best_lap.time_seconds,
                "crashes": _crashes(finish),
                "offtracks": finish.result.total_offtracks,
                "resets": sum(lap.resets for lap in finish.result.laps),
                "laps": [lap.to_json() for lap in finish.result.laps],
                **({"trace_file": str(traces[finish.car])} if finish.car in traces else {}),
            }
            for finish in result.cars
        ],
        "incidents": [
            {
                "clock_seconds": round(incident.clock, 3),
                "kind": incident.kind,
                "grid": incident.car + 1,
                "other_grid": incident.other + 1,
            }
            for incident in result.incidents
        ],
    }

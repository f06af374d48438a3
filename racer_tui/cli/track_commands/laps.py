"""`racer-tui tracks show`, `tracks line` and `tracks generate`: what a track allows (its
limit lap, the league's lap floor, the reference driver's lap), its racing line, and new
tracks. These load the simulator."""

from __future__ import annotations

import math
from pathlib import Path

from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from racer_tui.cli.track_commands import TrackOptionError
from racer_tui.cli.track_commands.listing import one_track_table
from sim.coach.limit_lap import limit_lap
from sim.coach.plausible import fastest_possible_lap
from sim.coach.reward_line import command_rows, line_comment, python_line
from sim.deepracer.action_space import ActionSpace
from sim.garage.folder import ModelError, open_model
from sim.physics.reference_driver import reference_lap
from sim.tracks.catalog import find_track_info, resolve_track, save_user_track
from sim.tracks.generator import generate_track


def _model_space(model: str | None) -> ActionSpace | None:
    if model is None:
        return None

    try:
        return open_model(model).metadata().action_space
    except ModelError as error:  # said as the garage says it, for --model
        raise TrackOptionError(str(error)) from None


def _facts(track_name: str, model: str | None) -> dict[str, object]:

    track = resolve_track(track_name)
    space = _model_space(model)
    lap = reference_lap(track)
    facts = dict(track.summary())
    if not Path(track_name).suffix:
        info = find_track_info(track_name)
        facts["kind"] = info.kind
        facts["console_name"] = info.console_name
        facts["release_date"] = info.release_date
    limit = limit_lap(track)
    facts["limit_flying_lap_s"] = round(limit.flying_seconds, 3)
    facts["limit_standing_lap_s"] = round(limit.standing_seconds, 3)
    # The league's floor: no lap under it is accepted anywhere (sim.coach.plausible).
    facts["lap_floor_s"] = round(fastest_possible_lap(track), 3)
    if space is not None:
        within = limit_lap(track, space=space)
        facts["model"] = model
        facts["model_limit_flying_lap_s"] = round(within.flying_seconds, 3)
        facts["model_limit_standing_lap_s"] = round(within.standing_seconds, 3)
    facts["reference_lap_s"] = None if math.isnan(lap.lap_time) else round(lap.lap_time, 3)
    facts["reference_status"] = lap.status
    facts["content_hash"] = track.content_hash
    return facts


def line(track_name: str, model: str | None, every: float, as_python: bool, as_json: bool) -> int:

    if not every > 0.0:
        raise TrackOptionError(f"--every must be a positive number of metres, not {every:g}.")
    track = resolve_track(track_name)
    space = _model_space(model)
    lap = limit_lap(track, space=space)
    rows = command_rows(lap, every, space=space)
    if as_json:
        print_json(
            {
                "track": track.name,
                "limits": lap.limits,
                "flying_lap_s": round(lap.flying_seconds, 3),
                "standing_lap_s": round(lap.standing_seconds, 3),
                "columns": ["x", "y", "speed"],
                "speed": "to command (params['speed']): the car drives a little faster",
                "points": rows,
            }
        )
    elif as_python:
        print(python_line(rows, line_comment(lap, every)))
    else:
        print("x,y,speed")
        for x, y, v in rows:
            print(f"{x},{y},{v}")
    return 0


def show(track_name: str, model: str | None, as_json: bool) -> int:
    facts = _facts(track_name, model)
    if as_json:
        print_json(facts)
        return 0
    table = Table(show_header=False, title=Text(str(facts["name"])))
    table.add_column("fact")
    table.add_column("value")
    for key, value in facts.items():
        table.add_row(key, Text("-" if value is None else str(value)))
    print_table(table)
    print(f"No lap under {facts['lap_floor_s']:.3f} s is accepted (DeepRacer's rules at 4 m/s).")
    return 0


def generate(seed: int, width: float, save: bool, as_json: bool) -> int:

    track = generate_track(seed, width=width)
    saved_as = save_user_track(track).name if save else None
    if as_json:
        summary = dict(track.summary())
        summary["seed"] = seed
        summary["saved"] = saved_as is not None
        print_json(summary)
        return 0
    title = f"Generated {track.name}" + (" (saved)" if saved_as else "")
    print_table(one_track_table(title, track.length, track.width, track.direction))
    return 0

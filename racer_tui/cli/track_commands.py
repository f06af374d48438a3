"""`racer-tui tracks ...`: list, show, import and generate tracks.

Listing reads catalogs only; the simulator (reference laps, the generator) is imported by
the actions that use it, so `racer-tui tracks list` answers at once.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from sim.foundation.remedies import RemedyError
from sim.tracks.catalog import (
    TrackInfo,
    find_track_info,
    import_track,
    list_tracks,
    resolve_track,
    save_user_track,
)

if TYPE_CHECKING:  # `tracks list` imports no simulator
    from sim.deepracer.action_space import ActionSpace

NAMES = ("tracks",)


class TrackOptionError(RemedyError):
    """An option of a tracks command that cannot be used; the message says which and why."""


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    tracks = commands.add_parser("tracks", help="list, show, import and generate tracks")
    track_commands = tracks.add_subparsers(dest="tracks_command", metavar="ACTION", required=True)
    listing = track_commands.add_parser(
        "list", help="built-in, official (AWS DeepRacer) and imported tracks"
    )
    listing.add_argument(
        "--search", metavar="TEXT", help="only tracks whose name or console name holds TEXT"
    )
    kinds = listing.add_argument_group("kinds (any combination; all when none is given)")
    kinds.add_argument("--builtin", action="store_true", help="racer-tui's own designs")
    kinds.add_argument("--official", action="store_true", help="AWS DeepRacer's tracks")
    kinds.add_argument("--imported", action="store_true", help="tracks you imported")
    listing.add_argument("--json", action="store_true", help="print JSON instead of a table")
    show = track_commands.add_parser(
        "show", help="one track's facts, its limit laps and its reference lap"
    )
    show.add_argument("track", help="track name (world or console name) or .npy file")
    show.add_argument(
        "--model", metavar="MODEL", help="also the limit laps within MODEL's action space"
    )
    show.add_argument("--json", action="store_true")
    line = track_commands.add_parser(
        "line",
        help="the limit lap's racing line with the speed to command (CSV, or --python / --json)",
    )
    line.add_argument("track", help="track name (world or console name) or .npy file")
    line.add_argument(
        "--model", metavar="MODEL", help="the line within MODEL's action space (its speeds)"
    )
    line.add_argument(
        "--every", type=float, default=0.1, metavar="METRES", help="metres between points"
    )
    shape = line.add_mutually_exclusive_group()
    shape.add_argument(
        "--python", action="store_true", help="a Python list a reward function can paste"
    )
    shape.add_argument("--json", action="store_true")
    importer = track_commands.add_parser("import", help="import a DeepRacer .npy track file")
    importer.add_argument("file", help="DeepRacer track file (.npy, shape N x 6)")
    importer.add_argument("--name", help="name to store it under (default: the file name)")
    importer.add_argument("--reverse", action="store_true", help="drive it the other way round")
    importer.add_argument("--description", default="")
    generate = track_commands.add_parser("generate", help="generate a random valid track")
    generate.add_argument("--seed", type=int, required=True)
    generate.add_argument("--width", type=float, default=0.76, help="road width in metres")
    generate.add_argument("--save", action="store_true", help="save it with your tracks")
    generate.add_argument("--json", action="store_true")


def run(args: argparse.Namespace) -> int:
    action = args.tracks_command
    if action == "list":
        kinds = {
            kind
            for kind, wanted in (
                ("built-in", args.builtin),
                ("official", args.official),
                ("imported", args.imported),
            )
            if wanted
        }
        return _list(_filtered(list_tracks(), args.search, kinds), args.json)
    if action == "show":
        return _show(args.track, args.model, args.json)
    if action == "line":
        return _line(args.track, args.model, args.every, args.python, args.json)
    if action == "import":
        return _import(Path(args.file), args.name, args.reverse, args.description)
    return _generate(args.seed, args.width, args.save, args.json)


def _filtered(infos: list[TrackInfo], search: str | None, kinds: set[str]) -> list[TrackInfo]:
    needle = (search or "").casefold()
    return [
        info
        for info in infos
        if (not kinds or info.kind in kinds)
        and (needle in info.name.casefold() or needle in info.console_name.casefold())
    ]


def _list(infos: list[TrackInfo], as_json: bool) -> int:
    if as_json:
        print_json(
            [
                {
                    "name": info.name,
                    "console_name": info.console_name,
                    "kind": info.kind,
                    "builtin": info.builtin,
                    "length_m": info.length_m,
                    "width_m": info.width_m,
                    "direction": info.direction,
                    "release_date": info.release_date,
                    "lappable": info.lappable,
                    "description": info.description,
                }
                for info in infos
            ]
        )
        return 0
    if not infos:
        print("No track matches; `racer-tui tracks list` shows them all.")
        return 0
    # One table per kind, one line per track, so 132 tracks read well at 80 columns.
    for kind, heading in _GROUPS:
        group = [info for info in infos if info.kind == kind]
        if group:
            print_table(_kind_table(f"{heading} ({len(group)})", group, kind))
    print("Give a track by its name or console name, e.g. --track reinvent_base.")
    return 0


def _kind_table(title: str, infos: list[TrackInfo], kind: str) -> Table:
    table = Table(
        title=title, title_justify="left", box=None, pad_edge=False, header_style="bold underline"
    )
    table.add_column("name", no_wrap=True, min_width=max(len(info.name) for info in infos))
    # What the console calls it; racer-tui's and your own tracks are not in the console,
    # and the column says what it holds for them: their description.
    second = "console name" if kind == "official" else "description"
    table.add_column(second, no_wrap=True, overflow="ellipsis", max_width=22)
    table.add_column("len m", justify="right", no_wrap=True)
    table.add_column("wide", justify="right", no_wrap=True)
    table.add_column("dir", no_wrap=True)
    table.add_column("released", no_wrap=True)  # the month: the day is in --json
    for info in infos:
        # Names and descriptions are user data: Text() keeps them plain, never markup.
        table.add_row(
            Text(info.name),
            Text(_console_or_description(info)),
            f"{info.length_m:.2f}",
            f"{info.width_m:.2f}",
            _DIRECTIONS.get(info.direction, info.direction),
            info.release_date[:7] or "-",
        )
    return table


_GROUPS = (
    ("built-in", "Built-in: racer-tui's designs"),
    ("official", "Official: AWS DeepRacer's tracks"),
    ("imported", "Imported: your tracks"),
)


def _console_or_description(info: TrackInfo) -> str:
    if info.kind == "official":
        return info.console_name or "(not in the console)"
    return info.description or "-"


_DIRECTIONS = {"counter-clockwise": "ccw", "clockwise": "cw", "straight": "-"}


def _model_space(model: str | None) -> ActionSpace | None:
    if model is None:
        return None
    from sim.garage.folder import ModelError, open_model

    try:
        return open_model(model).metadata().action_space
    except ModelError as error:  # said as the garage says it, for --model
        raise TrackOptionError(str(error)) from None


def _facts(track_name: str, model: str | None) -> dict[str, object]:
    from sim.coach.limit_lap import limit_lap
    from sim.coach.plausible import fastest_possible_lap
    from sim.physics.reference_driver import reference_lap

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


def _line(track_name: str, model: str | None, every: float, as_python: bool, as_json: bool) -> int:
    from sim.coach.limit_lap import limit_lap
    from sim.coach.reward_line import command_rows, line_comment, python_line

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


def _show(track_name: str, model: str | None, as_json: bool) -> int:
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


def _import(file: Path, name: str | None, reverse: bool, description: str) -> int:
    info = import_track(file, name, reverse=reverse, description=description)
    title = (
        f"Imported {info.name}"
        if info.kind == "imported"
        else f"{info.title} is already here as {_a(info.kind)} track; nothing was copied"
    )
    print_table(_one_track_table(title, info.length_m, info.width_m, info.direction))
    return 0


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def _generate(seed: int, width: float, save: bool, as_json: bool) -> int:
    from sim.tracks.generator import generate_track

    track = generate_track(seed, width=width)
    saved_as = save_user_track(track).name if save else None
    if as_json:
        summary = dict(track.summary())
        summary["seed"] = seed
        summary["saved"] = saved_as is not None
        print_json(summary)
        return 0
    title = f"Generated {track.name}" + (" (saved)" if saved_as else "")
    print_table(_one_track_table(title, track.length, track.width, track.direction))
    return 0


def _one_track_table(title: str, length: float, width: float, direction: str) -> Table:
    table = Table(title=Text(title))
    table.add_column("length")
    table.add_column("width")
    table.add_column("direction")
    table.add_row(f"{length:.2f} m", f"{width:.3f} m", direction)
    return table

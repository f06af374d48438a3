"""`racer-tui tracks ...`: list, show, import and generate tracks."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.table import Table
from rich.text import Text

from racer_tui.output import print_json, print_table
from sim.reference_driver import reference_lap
from sim.track_catalog import import_track, list_tracks, resolve_track, save_user_track
from sim.track_generator import generate_track

NAMES = ("tracks",)


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    tracks = commands.add_parser("tracks", help="list, show, import and generate tracks")
    track_commands = tracks.add_subparsers(dest="tracks_command", metavar="ACTION", required=True)
    listing = track_commands.add_parser("list", help="built-in and imported tracks")
    listing.add_argument("--json", action="store_true", help="print JSON instead of a table")
    show = track_commands.add_parser("show", help="one track's facts and its reference lap")
    show.add_argument("track", help="track name or .npy file")
    show.add_argument("--json", action="store_true")
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
        return _list(args.json)
    if action == "show":
        return _show(args.track, args.json)
    if action == "import":
        return _import(Path(args.file), args.name, args.reverse, args.description)
    return _generate(args.seed, args.width, args.save, args.json)


def _list(as_json: bool) -> int:
    infos = list_tracks()
    if as_json:
        print_json(
            [
                {
                    "name": info.name,
                    "description": info.description,
                    "length_m": info.length_m,
                    "width_m": info.width_m,
                    "direction": info.direction,
                    "builtin": info.builtin,
                }
                for info in infos
            ]
        )
        return 0
    table = Table(title="Tracks")
    table.add_column("name", no_wrap=True)
    table.add_column("length", justify="right", no_wrap=True)
    table.add_column("width", justify="right", no_wrap=True)
    table.add_column("dir", no_wrap=True)
    table.add_column("kind", no_wrap=True)
    table.add_column("description", ratio=1, min_width=20)
    for info in infos:
        # Names and descriptions are user data: Text() keeps them plain, never markup.
        table.add_row(
            Text(info.name),
            f"{info.length_m:.2f} m",
            f"{info.width_m:.3f} m",
            "ccw" if info.direction == "counter-clockwise" else "cw",
            "built-in" if info.builtin else "imported",
            Text(info.description),
        )
    print_table(table)
    return 0


def _facts(track_name: str) -> dict[str, object]:
    track = resolve_track(track_name)
    lap = reference_lap(track)
    facts = dict(track.summary())
    facts["reference_lap_s"] = None if math.isnan(lap.lap_time) else round(lap.lap_time, 3)
    facts["reference_status"] = lap.status
    facts["content_hash"] = track.content_hash
    return facts


def _show(track_name: str, as_json: bool) -> int:
    facts = _facts(track_name)
    if as_json:
        print_json(facts)
        return 0
    table = Table(show_header=False, title=Text(str(facts["name"])))
    table.add_column("fact")
    table.add_column("value")
    for key, value in facts.items():
        table.add_row(key, Text("-" if value is None else str(value)))
    print_table(table)
    return 0


def _import(file: Path, name: str | None, reverse: bool, description: str) -> int:
    info = import_track(file, name, reverse=reverse, description=description)
    print_table(
        _one_track_table(f"Imported {info.name}", info.length_m, info.width_m, info.direction)
    )
    return 0


def _generate(seed: int, width: float, save: bool, as_json: bool) -> int:
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

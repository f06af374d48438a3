"""`racer-tui tracks ...`: list, show, import and generate tracks.

Listing reads catalogs only; the simulator (reference laps, the generator) is imported by
the actions that use it, so `racer-tui tracks list` answers at once.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from racer_tui.cli.track_commands import listing
from sim.foundation.remedies import RemedyError
from sim.tracks.catalog import list_tracks

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
        return listing.list_tracks_table(
            listing.filtered(list_tracks(), args.search, kinds), args.json
        )
    if action == "import":
        return listing.import_track_file(Path(args.file), args.name, args.reverse, args.description)
    # Imported only for these actions: they load the simulator, which `tracks list` and the
    # app's start do not need.
    laps = importlib.import_module(f"{__name__}.laps")
    if action == "show":
        result: int = laps.show(args.track, args.model, args.json)
    elif action == "line":
        result = laps.line(args.track, args.model, args.every, args.python, args.json)
    else:
        result = laps.generate(args.seed, args.width, args.save, args.json)
    return result

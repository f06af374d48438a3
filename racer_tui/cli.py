"""The `racer-tui` command: the Textual app by default, headless subcommands for scripts.

This module never imports textual at module level, so headless commands start fast.
A user error is one sentence on stderr and exit code 2; never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import Any

from rich.console import Console
from rich.table import Table

from sim.action_space import ActionSpaceError
from sim.observations import SensorError
from sim.track import TrackError

EXIT_USER_ERROR = 2


class UsageError(Exception):
    """A wrong command line; the message says what to type instead."""


def _user_errors() -> tuple[type[Exception], ...]:
    from sim.reward_function import RewardFunctionError

    return (TrackError, ActionSpaceError, SensorError, RewardFunctionError, UsageError)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="racer-tui",
        description="Build, train and race AWS-DeepRacer-style car models in the terminal.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

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

    reward = commands.add_parser("reward", help="check a reward function")
    reward_commands = reward.add_subparsers(dest="reward_command", metavar="ACTION", required=True)
    check = reward_commands.add_parser("check", help="run a reward function on sample params")
    check.add_argument("file", help="Python file defining reward_function(params)")
    check.add_argument("--track", default=None, help="also score a reference lap on this track")
    check.add_argument("--json", action="store_true")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command is None:
        from racer_tui.app import run_app

        return run_app()
    try:
        return _dispatch(args)
    except _user_errors() as exc:
        # Plain print: one unwrapped sentence, and no markup interpretation of user text.
        print(f"racer-tui: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        return 130


def _dispatch(args: argparse.Namespace) -> int:
    if args.command == "tracks":
        from racer_tui import track_commands

        return track_commands.run(args)
    if args.command == "reward":
        from racer_tui import reward_commands

        return reward_commands.run(args)
    raise UsageError(f"unknown command {args.command!r}; see racer-tui --help.")


def print_json(document: Any) -> None:
    sys.stdout.write(json.dumps(document, indent=2, sort_keys=False) + "\n")


def print_table(table: Table) -> None:
    Console().print(table)


if __name__ == "__main__":
    raise SystemExit(main())

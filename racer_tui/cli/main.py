"""The `racer-tui` command: the Textual app by default, headless subcommands for scripts.

This module never imports textual at module level, and a subcommand imports only its own
command module, so headless commands start fast (`racer-tui tracks list` loads no
simulator). A user error is one sentence on stderr and exit code 2; never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from league.timekeeper.feed import TIMER_ENV, check_timer_path
from racer_tui.cli.app_launch import AppLaunch
from sim.foundation.home import LEAGUE_ENV
from sim.foundation.remedies import RemedyError

EXIT_USER_ERROR = 2
_NEGATIVE_VALUE = re.compile(r"-\d[\d.]*(,\s*-?\d[\d.]*)+")  # "-30,30", "-1.5,-0.5"
# One module per command group, with the subcommands it registers (its NAMES; a test keeps
# the two in step), so a command is dispatched without importing the other groups.
COMMAND_MODULES: dict[str, tuple[str, ...]] = {
    "racer_tui.cli.track_commands": ("tracks",),
    "racer_tui.cli.reward_commands": ("reward",),
    "racer_tui.cli.model_commands": ("model",),
    "racer_tui.cli.league_commands": (
        "submit",
        "leaderboard",
        "night",
        "season",
        "racer",
        "correct",
    ),
    "racer_tui.cli.train_commands": ("train", "evaluate"),
    "racer_tui.cli.sync_commands": ("sync",),
    "racer_tui.cli.coach_commands": ("coach",),
    "racer_tui.cli.serve_commands": ("serve",),
}


class UsageError(RemedyError):
    """A wrong command line; the message says what to type instead."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole parser, or (given a known subcommand) one holding only that group's."""
    parser = argparse.ArgumentParser(
        prog="racer-tui",
        description="Build, train and race AWS-DeepRacer-style car models in the terminal.",
        epilog="Headless time trials: racer-tui --race MODEL [MODEL ...] --track TRACK "
        "(see racer-tui --race --help).",
    )
    parser.add_argument(
        "--db",
        dest="league_db",
        metavar="FILE",
        help="the league database for the app and every command (default: league.db in the "
        f"data folder, or ${LEAGUE_ENV}); a command's own --db still wins",
    )
    parser.add_argument(
        "--timer",
        metavar="PATH",
        help="an automatic lap timer for the app's timekeeper: a serial device or named pipe "
        "sending a line 'lap' as the car crosses the line and 'reset' for a car reset",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules(command):
        module.register(commands)
    return parser


def _command_modules(command: str | None = None) -> list[Any]:
    """Each command module has `NAMES` (its subcommands), `register(commands)` and `run(args)`.
    Given a subcommand, only its
    module; otherwise (help, the app, an unknown word) all of them."""
    names = [name for name, owns in COMMAND_MODULES.items() if command in owns]
    return [importlib.import_module(name) for name in names or COMMAND_MODULES]


def _attach_negative_values(arguments: list[str]) -> list[str]:
    """`--steering-range -30,30` as written: argparse takes "-30,30" for an option (it only
    knows plain negative numbers), so a value that starts with a minus and a digit is joined
    to the long option before it (`--steering-range=-30,30`)."""
    joined: list[str] = []
    for argument in arguments:
        previous = joined[-1] if joined else ""
        if (
            _NEGATIVE_VALUE.fullmatch(argument)
            and previous.startswith("--")
            and "=" not in previous
        ):
            joined[-1] = f"{previous}={argument}"
        else:
            joined.append(argument)
    return joined


def _subcommand(arguments: Sequence[str]) -> str | None:
    """The first word that is not an option or an option's value: the subcommand, if any."""
    skip_value = False
    for argument in arguments:
        if skip_value:
            skip_value = False
        elif argument in ("--db", "--timer"):
            skip_value = True
        elif not argument.startswith("-"):
            return argument
    return None


def main(argv: Sequence[str] | None = None) -> int:
    arguments = list(sys.argv[1:] if argv is None else argv)
    if "--race" in arguments:
        # Headless time trials are a top-level mode with their own parser.
        from racer_tui.cli.race_commands import main as race_main  # noqa: PLC0415 (the simulator: only for --race)

        return race_main(arguments)
    arguments = _attach_negative_values(arguments)
    args = build_parser(_subcommand(arguments)).parse_args(arguments)
    if args.league_db:
        # Through the environment, so the app's screens, the league commands and any child
        # process all open the same file without passing it along.
        os.environ[LEAGUE_ENV] = args.league_db
    if args.command is None:
        if args.timer:
            problem = check_timer_path(args.timer)
            if problem is not None:
                print(f"racer-tui: {problem}", file=sys.stderr)
                return EXIT_USER_ERROR
            os.environ[TIMER_ENV] = str(Path(args.timer).resolve())
        return _open_app()
    try:
        return _dispatch(args)
    except RemedyError as exc:  # every user error: one sentence
        # Plain print: one unwrapped sentence, and no markup interpretation of user text.
        print(f"racer-tui: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        # The reader went away (`racer-tui sync | head`): say nothing more, as `cat` does.
        # Point stdout at /dev/null so the interpreter's final flush cannot fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


def _dispatch(args: argparse.Namespace) -> int:
    for module in _command_modules(args.command):
        if args.command in module.NAMES:
            result = module.run(args)
            if isinstance(result, AppLaunch):
                return _open_app(result)
            return int(result)
    raise UsageError(f"unknown command {args.command!r}; see racer-tui --help.")


def _open_app(launch: AppLaunch | None = None) -> int:
    """The app, as the command line or a command asked: the one place the command line
    opens it (textual is imported only now)."""
    from racer_tui.app.application import run_app  # noqa: PLC0415 (textual: only when the app opens)

    launch = launch or AppLaunch()
    return run_app(projector_night=launch.projector_night, db_path=launch.db_path)


if __name__ == "__main__":
    raise SystemExit(main())

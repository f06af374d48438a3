"""`racer-tui reward check FILE`: does this reward function work, and what does it pay?

It runs the function on DeepRacer-complete sample params, then scores every step of the
reference driver's lap on a track, so a racer sees real values before training. The
function runs in a child process with a time limit (sim.reward.probe).
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from racer_tui.text.reward_lap import lap_chart
from racer_tui.text.reward_map import map_text
from sim.coach.reward_line import line_followed, template_source
from sim.deepracer.action_space import ActionSpace
from sim.deepracer.vocabulary import MAX_SPEED
from sim.foundation.atomic import write_bytes_atomic
from sim.foundation.remedies import RemedyError
from sim.garage.folder import open_model
from sim.reward.droa_check import DroaVerdict, droa_verdict
from sim.reward.function import read_reward_file
from sim.reward.lap import DEFAULT_SPEEDS, LINES, REFERENCE_LINE, line_verdict, verdict
from sim.reward.map import (
    DEFAULT_SPACING,
    DEFAULT_SPEED,
    MapOptions,
    png_bytes,
)
from sim.reward.probe import check_reward_source, lap_pay_of_source, map_reward_source
from sim.reward.sandbox import DEFAULT_MEMORY_MB, check_memory_mb
from sim.reward.template_files import TEMPLATES
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track

NAMES = ("reward",)


class MapOptionError(RemedyError):
    """A `reward map` option out of range; the message is one sentence."""


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    reward = commands.add_parser("reward", help="check a reward function")
    reward_commands = reward.add_subparsers(dest="reward_command", metavar="ACTION", required=True)
    check = reward_commands.add_parser("check", help="run a reward function on sample params")
    check.add_argument("file", help="Python file defining reward_function(params)")
    check.add_argument(
        "--track", default=None, help=f"score a reference lap on this track ({DEFAULT_TRACK})"
    )
    check.add_argument(
        "--reward-memory-mb",
        type=float,
        default=DEFAULT_MEMORY_MB,
        help=f"memory the function may use (default {DEFAULT_MEMORY_MB} MB)",
    )
    check.add_argument(
        "--strict",
        action="store_true",
        help="fail when DeepRacer on AWS's validator would refuse the function",
    )
    check.add_argument("--json", action="store_true")
    drawn = reward_commands.add_parser(
        "map", help="draw what a reward function pays everywhere on a track"
    )
    _function_arguments(drawn, "track and top speed")
    drawn.add_argument(
        "--speed", type=float, help="m/s (default 2, or the model's action space's top speed)"
    )
    drawn.add_argument(
        "--heading",
        default="track",
        help="'track' (along the road where the car stands) or fixed:DEGREES",
    )
    drawn.add_argument("--spacing", type=float, default=DEFAULT_SPACING, help="metres per cell")
    lap = reward_commands.add_parser(
        "lap",
        help="what a reward function pays along a lap of the centre line and of the "
        "reference driver's line at each speed: does it pay for speed?",
    )
    _function_arguments(lap, "track and action space's speeds")
    lap.add_argument(
        "--speeds",
        help="m/s, comma-separated (default 1,2,3,4, or the model's action space's speeds)",
    )
    lap.add_argument("--json", action="store_true")
    out = drawn.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="print the grid as JSON")
    out.add_argument("--png", metavar="FILE", help="write the map as a PNG image")


def _function_arguments(parser: argparse.ArgumentParser, model_gives: str) -> None:
    parser.add_argument(
        "function",
        nargs="?",
        help="a reward function file, or a template's name (omitted with --model)",
    )
    parser.add_argument(
        "--model", help=f"a garage model: its reward function, and its {model_gives} unless given"
    )
    parser.add_argument("--track", help=f"default {DEFAULT_TRACK}, or the model's")


@dataclass(frozen=True)
class _Subject:
    """What `reward map` and `reward lap` look at: a function's code and name, the track
    (as given: a .npy path is read again by the child, not looked up by name), and the
    model's action space when one was named."""

    source: str
    name: str  # as errors name it: the file's path, or the template's file
    track_name: str
    action_space: ActionSpace | None
    title: str  # as the racer named it: the file, the template, or "MODEL's reward function"


def _subject(args: argparse.Namespace) -> _Subject:
    if args.model is None:
        if args.function is None:
            raise MapOptionError(
                "Give a reward function file or a template's name, or --model NAME for a "
                "garage model's own function."
            )
        track_name = args.track or DEFAULT_TRACK
        source, name = _function(args.function, track_name, None)
        return _Subject(source, name, track_name, None, args.function)

    folder = open_model(args.model)
    space = folder.metadata().action_space
    own_track = folder.training_params().world_name
    track_name = args.track or own_track
    if args.function is not None:
        source, name = _function(args.function, track_name, space)
        return _Subject(source, name, track_name, space, args.function)
    title = f"{folder.name}'s reward function"
    source = folder.reward_source()
    if track_name != own_track:  # a racing_line reward pays for the line of the track mapped
        source = line_followed(source, (own_track, space), (track_name, space))
    return _Subject(source, str(folder.reward_file), track_name, space, title)


def run(args: argparse.Namespace) -> int:
    if args.reward_command == "map":
        return _map(args)
    if args.reward_command == "lap":
        return _lap(args)
    try:
        memory_mb = check_memory_mb(args.reward_memory_mb)
    except ValueError as error:
        raise MapOptionError(f"--reward-memory-mb: {error}.") from None
    source = read_reward_file(Path(args.file))
    track_name = args.track or DEFAULT_TRACK
    resolve_track(track_name)  # an unknown track is the racer's typo, said before any run
    # In a child process of its own session, with a time limit on every call and a memory
    # limit (sim.reward.sandbox): a function that loops, sleeps, exits its process, starts
    # one or allocates without bound is reported in one sentence, never hangs this
    # command, and leaves no process behind.
    probe = check_reward_source(source, str(args.file), track=track_name, memory_mb=memory_mb)
    # DeepRacer on AWS's validator, on the same track's route: a function racer-tui takes
    # may still be refused there (sim.reward.droa_rules).
    droa = droa_verdict(source, str(args.file), track_name, memory_mb=memory_mb)
    lap_rewards = probe.lap_rewards or (0.0,)
    report: dict[str, Any] = {
        "file": str(args.file),
        "sample_params_reward": probe.sample_reward,
        "track": probe.track,
        "lap_steps": len(probe.lap_rewards),
        "lap_reward_min": float(np.min(lap_rewards)),
        "lap_reward_mean": float(np.mean(lap_rewards)),
        "lap_reward_max": float(np.max(lap_rewards)),
        "lap_reward_total": float(np.sum(probe.lap_rewards)),
        "files_closed_off": probe.landlock == "applied",
        "deepracer_on_aws": droa.to_json(),
    }
    if args.json:
        print_json(report)
        return _strict_exit(args, droa)
    table = Table(title=Text(f"Reward check: {args.file}"), show_header=False)
    table.add_column("what")
    table.add_column("value", justify="right")
    table.add_row("sample params", f"{probe.sample_reward:.4f}")
    table.add_row(Text(f"reference lap on {probe.track}"), f"{len(probe.lap_rewards)} steps")
    for key in ("min", "mean", "max", "total"):
        table.add_row(f"  reward {key}", f"{report['lap_reward_' + key]:.4f}")
    print_table(table)
    print("OK: the function ran on every step without an error.")
    _print_droa(droa)
    if probe.landlock != "applied":
        # Said, not failed: the racer learns that this system cannot keep the code from
        # their files (the audit guard still holds what it can: sim.reward.guard).
        print(
            f"Note: {probe.landlock}, so only Python's audit hooks kept this function from "
            "your files; read a function you did not write before you run it."
        )
    return _strict_exit(args, droa)


class DroaRefusedError(RemedyError):
    """`reward check --strict` on a function DeepRacer on AWS would refuse."""


def _print_droa(droa: DroaVerdict) -> None:
    where = f"its validator's rules, on {droa.track}"
    if droa.accepted:
        print(f"DeepRacer on AWS would accept it ({where}).")
        return
    table = Table(
        title=Text(f"DeepRacer on AWS would refuse it ({where}); it says the first"),
        show_header=True,
    )
    table.add_column("line", justify="right")
    table.add_column("type")
    table.add_column("DeepRacer on AWS says")
    for reason in droa.reasons:
        line = "" if reason.line is None else str(reason.line)
        table.add_row(line, Text(reason.kind), Text(reason.message.strip()))
    print_table(table)


def _strict_exit(args: argparse.Namespace, droa: DroaVerdict) -> int:
    if not args.strict or droa.accepted:
        return 0
    first = droa.reasons[0]
    where = f" (line {first.line})" if first.line is not None else ""
    raise DroaRefusedError(
        f'{args.file}: DeepRacer on AWS would refuse it{where}, saying "'
        f'{first.message.strip()}"; fix that, or check without --strict.'
    )


# --- map -----------------------------------------------------------------------------------


def _map(args: argparse.Namespace) -> int:
    subject = _subject(args)
    speed = args.speed
    if speed is None:
        space = subject.action_space
        speed = DEFAULT_SPEED if space is None else space.max_speed
    options = MapOptions(args.spacing, speed, _heading(args.heading))
    if not (0.02 <= options.spacing <= 1.0):
        raise MapOptionError(f"--spacing must be from 0.02 to 1 m, not {options.spacing:g}.")
    if not (0.0 < options.speed <= MAX_SPEED):
        raise MapOptionError(f"--speed must be above 0 and at most {MAX_SPEED:g} m/s.")
    track = resolve_track(subject.track_name)
    reward_map = map_reward_source(subject.source, subject.name, subject.track_name, options)
    if args.json:
        print_json(reward_map.to_json())
    elif args.png:
        write_bytes_atomic(Path(args.png), png_bytes(reward_map, track=track))
        print(f"Wrote {args.png}.")
    else:
        Console().print(map_text(reward_map, shutil.get_terminal_size().columns, track=track))
    if reward_map.first_failure:
        print(
            f"The function failed on {len(reward_map.failed)} cells (red): "
            f"{reward_map.first_failure}",
            file=sys.stderr,
        )
    return 0


def _heading(text: str) -> float | None:
    if text == "track":
        return None
    degrees = text.removeprefix("fixed:")
    try:
        value = float(degrees)
    except ValueError:
        raise MapOptionError(
            f"--heading must be 'track' or fixed:DEGREES (for example fixed:90), not {text!r}."
        ) from None
    if not math.isfinite(value):
        raise MapOptionError(f"--heading must be a number of degrees, not {text!r}.")
    return value


def _function(given: str, track_name: str, space: ActionSpace | None) -> tuple[str, str]:
    """(source, name) of a template's name (racing_line with the line of `track_name`) or a
    reward function file (read, not run)."""
    if given in TEMPLATES:
        return template_source(given, track_name, space), TEMPLATES[given]
    return read_reward_file(Path(given)), given


def _lap(args: argparse.Namespace) -> int:
    subject = _subject(args)
    space = subject.action_space
    if args.speeds is not None:
        speeds = _speeds(args.speeds)
    else:
        speeds = DEFAULT_SPEEDS if space is None else space.speeds()
    track = resolve_track(subject.track_name)
    pays = lap_pay_of_source(
        subject.source, subject.name, subject.track_name, tuple(sorted(set(speeds)))
    )
    if args.json:
        print_json({"track": track.name, "laps": [pay.to_json() for pay in pays]})
        return 0
    console = Console()
    console.print(Text(f"One lap of {track.name}: {subject.title}", style="bold"))
    console.print(lap_chart(pays, shutil.get_terminal_size().columns))
    missing = [line for line in LINES if line not in {pay.line for pay in pays}]
    said = [verdict(pays), line_verdict(pays)]
    if REFERENCE_LINE in missing:
        said.append(
            f"The reference driver does not finish a lap of {track.name}, so only the centre "
            "line is charted."
        )
    for sentence in said:
        if sentence is not None:
            console.print(Text(sentence))  # wrapped to the terminal, never read as markup
    return 0


def _speeds(text: str) -> tuple[float, ...]:
    try:
        speeds = tuple(float(part) for part in text.split(","))
    except ValueError:
        raise MapOptionError(
            f"--speeds must be m/s separated by commas, for example 1,2,3,4, not {text!r}."
        ) from None
    if not speeds or not all(0.1 <= speed <= MAX_SPEED for speed in speeds):
        raise MapOptionError(f"--speeds must each be from 0.1 to {MAX_SPEED:g} m/s.")
    return speeds

"""`racer-tui model ...`: the garage from the command line.

new, list, show, clone, delete, import (a DeepRacer folder or a bundle) and export (a
bundle). The library is `sim.garage`; this module parses options and prints.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from rich.table import Table
from rich.text import Text

from racer_tui.cli.output import print_json, print_table
from sim.car_archive.errors import CarModelError
from sim.car_archive.file_names import is_car_archive_name
from sim.car_export.act import archive_answer, model_answer
from sim.car_export.frame import read_picture
from sim.deepracer.vocabulary import MAX_SPEED, MAX_STEERING, MIN_SPEED
from sim.garage.bundle import export_bundle
from sim.garage.clone import clone_model
from sim.garage.deepracer_notes import export_notes
from sim.garage.droa_export import refuse_droa_export
from sim.garage.folder import (
    ModelError,
    ModelFolder,
    delete_model,
    export_target,
    list_models,
    open_model,
)
from sim.garage.importing import import_model
from sim.garage.options import (
    DEFAULT_BOT_SPEED,
    DEFAULT_BOTS,
    DEFAULT_MAX_SPEED,
    DEFAULT_MAX_STEERING,
    DEFAULT_MINUTES,
    DEFAULT_OBSTACLES,
    DEFAULT_REWARD,
    DEFAULT_SENSORS,
    DEFAULT_SPEED_LEVELS,
    DEFAULT_STEERING_LEVELS,
    DEFAULT_TRACK,
    LINE_ACTIONS,
    new_model,
    parse_hp_assignments,
    parse_range,
)
from sim.garage.overview import model_details, model_row, network_words
from sim.sensors.randomisation.settings import parse_camera_randomisation

NAMES = ("model",)


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    model = commands.add_parser("model", help="create, list, clone, import and export models")
    actions = model.add_subparsers(dest="model_command", metavar="ACTION", required=True)

    new = actions.add_parser("new", help="create a model, with options like the DeepRacer console")
    new.add_argument("name", help="model name (letters, digits, '-' and '_')")
    _add_spec_options(new, for_clone=False)
    new.add_argument("--json", action="store_true", help="print the new model as JSON")

    listing = actions.add_parser("list", help="your models and their state")
    listing.add_argument("--json", action="store_true")

    show = actions.add_parser("show", help="everything about one model")
    show.add_argument("name", help="model name or folder")
    show.add_argument("--json", action="store_true")

    clone = actions.add_parser("clone", help="a new model that continues from a trained one")
    clone.add_argument("source", help="model to clone")
    clone.add_argument("name", help="name of the clone")
    _add_spec_options(clone, for_clone=True)
    clone.add_argument("--json", action="store_true")

    delete = actions.add_parser("delete", help="delete a model folder")
    delete.add_argument("name")
    delete.add_argument("--yes", action="store_true", help="do not ask")

    importer = actions.add_parser(
        "import",
        help="import a DeepRacer model folder, a .racer-bundle, or a car archive (.tar.gz)",
    )
    importer.add_argument(
        "path",
        help="DeepRacer model folder, .racer-bundle file, or the .tar.gz a DeepRacer car loads",
    )
    importer.add_argument("--name", help="name in your garage (default: the folder's/bundle's)")
    importer.add_argument("--track", help=f"track to train on (default: {DEFAULT_TRACK})")
    importer.add_argument(
        "--untrained",
        action="store_true",
        help="leave a DeepRacer folder's own weights (model_N.pb) behind, to train it here",
    )
    importer.add_argument("--json", action="store_true")

    act = actions.add_parser(
        "act", help="what a model does with a camera picture, as a DeepRacer car runs it"
    )
    act.add_argument("name", help="model name or folder, or a car archive (.tar.gz)")
    act.add_argument("picture", help="a PNG or JPEG picture, any size (e.g. from your car)")
    act.add_argument("--json", action="store_true")

    export = actions.add_parser(
        "export", help="write a model as a .racer-bundle, or as the archive a DeepRacer car loads"
    )
    export.add_argument("name")
    export.add_argument(
        "--format",
        choices=("bundle", "car", "droa"),
        default="bundle",
        help="bundle: racer-tui's own file (default); car: NAME.tar.gz for a physical DeepRacer; "
        "droa: refused, with the reason (docs/deepracer/deepracer-on-aws.md)",
    )
    export.add_argument(
        "-o", "--output", help="file to write (default: NAME.racer-bundle, or NAME.tar.gz)"
    )
    export.add_argument("--force", action="store_true", help="replace an existing file")
    export.add_argument("--json", action="store_true", help="print what was written as JSON")


def _add_spec_options(parser: argparse.ArgumentParser, *, for_clone: bool) -> None:
    def default(text: str) -> str:
        return "default: the source's" if for_clone else f"default: {text}"

    parser.add_argument("--track", help=f"track name ({default(DEFAULT_TRACK)})")
    parser.add_argument(
        "--sensor",
        action="append",
        metavar="SENSOR",
        help="camera, lidar, sector_lidar, vector or DeepRacer's names such as "
        f"FRONT_FACING_CAMERA; repeat or comma-separate ({default('+'.join(DEFAULT_SENSORS))})",
    )
    grid = parser.add_argument_group("discrete action space, as the console builds it")
    grid.add_argument(
        "--max-steering",
        type=float,
        metavar="DEG",
        help=f"1-{MAX_STEERING:g} degrees (default {DEFAULT_MAX_STEERING:g})",
    )
    grid.add_argument(
        "--steering-levels",
        type=int,
        metavar="N",
        help=f"3, 5 or 7 (default {DEFAULT_STEERING_LEVELS})",
    )
    grid.add_argument(
        "--max-speed",
        type=float,
        metavar="M/S",
        help=f"{MIN_SPEED:g}-{MAX_SPEED:g} m/s (default {DEFAULT_MAX_SPEED:g})",
    )
    grid.add_argument(
        "--speed-levels", type=int, metavar="N", help=f"1, 2 or 3 (default {DEFAULT_SPEED_LEVELS})"
    )
    parser.add_argument(
        "--actions",
        type=Path,
        metavar="FILE.json",
        help="an explicit action list (or a model_metadata.json)",
    )
    line = parser.add_argument_group("discrete action space from the track's racing line")
    line.add_argument(
        "--actions-from-line",
        action="store_true",
        help="the actions the limit lap's line asks for, clustered (racer-tui tracks line)",
    )
    line.add_argument(
        "--action-count",
        type=int,
        metavar="N",
        help=f"at most how many actions --actions-from-line makes, 3-30 (default {LINE_ACTIONS})",
    )
    continuous = parser.add_argument_group("continuous action space")
    continuous.add_argument("--continuous", action="store_true")
    continuous.add_argument(
        "--steering-range",
        metavar="LOW,HIGH",
        help=f"degrees (default {-MAX_STEERING:g},{MAX_STEERING:g})",
    )
    continuous.add_argument(
        "--speed-range", metavar="LOW,HIGH", help=f"m/s (default {MIN_SPEED:g},{MAX_SPEED:g})"
    )
    parser.add_argument(
        "--camera-randomisation",
        metavar="WHAT",
        help="a camera model trains for the real world: on, off"
        f"{'' if for_clone else ' (default)'}, or families from light, noise, blur, pose, "
        "colours with strengths (e.g. light,noise=0.5)",
    )
    race = parser.add_argument_group("race type")
    race.add_argument(
        "--race-type",
        metavar="TYPE",
        help="time-trial (default), object-avoidance (boxes on the track) or head-to-bot "
        "(bot cars driving it)",
    )
    race.add_argument(
        "--obstacles",
        type=int,
        metavar="N",
        help=f"boxes in an object-avoidance race, 1-10 (default {DEFAULT_OBSTACLES})",
    )
    race.add_argument(
        "--randomize-obstacles",
        action="store_true",
        help="place the boxes again, at random, every episode",
    )
    race.add_argument(
        "--bots",
        type=int,
        metavar="N",
        help=f"bot cars in a head-to-bot race, 1-6 (default {DEFAULT_BOTS})",
    )
    race.add_argument(
        "--bot-speed",
        type=float,
        metavar="M/S",
        help=f"the bot cars' speed (default {DEFAULT_BOT_SPEED:g} m/s)",
    )
    race.add_argument(
        "--bot-lane-change",
        action="store_true",
        help="bot cars change lanes every 3-5 s",
    )
    parser.add_argument(
        "--reward",
        metavar="TEMPLATE|FILE",
        help=f"a template name or a reward function file ({default(DEFAULT_REWARD)})",
    )
    parser.add_argument(
        "--hp",
        action="extend",
        nargs="+",
        default=[],
        metavar="KEY=VALUE",
        help="hyperparameters with DeepRacer's keys, e.g. --hp lr=0.0001 batch_size=128",
    )
    parser.add_argument(
        "--minutes",
        type=float,
        help=f"training time limit ({default(f'{DEFAULT_MINUTES:g}')})",
    )


def run(args: argparse.Namespace) -> int:
    action = args.model_command
    if action == "new":
        return _new(args)
    if action == "list":
        return _list(args.json)
    if action == "show":
        return _show(args.name, args.json)
    if action == "clone":
        return _clone(args)
    if action == "delete":
        return _delete(args.name, args.yes)
    if action == "import":
        return _import(args)
    if action == "act":
        return _act(args.name, Path(args.picture), as_json=args.json)
    if args.format == "droa":
        open_model(args.name)  # a typo in the name is said first
        refuse_droa_export()
    if args.format == "car":
        return _export_car(args.name, args.output, replace=args.force, as_json=args.json)
    return _export(args.name, args.output, replace=args.force, as_json=args.json)


# --- new and clone ---------------------------------------------------------------------------


def _spec_options(args: argparse.Namespace) -> dict[str, Any]:
    """The `model_spec` keyword options the command line gave (unset ones are left out)."""
    options: dict[str, Any] = {
        "track": args.track,
        "max_steering": args.max_steering,
        "steering_levels": args.steering_levels,
        "max_speed": args.max_speed,
        "speed_levels": args.speed_levels,
        "actions_file": args.actions,
        "reward": args.reward,
        "minutes": args.minutes,
    }
    if args.sensor:
        options["sensors"] = [part.strip() for item in args.sensor for part in item.split(",")]
    if args.continuous:
        options["continuous"] = True
    if args.action_count is not None and not args.actions_from_line:
        raise ModelError("--action-count needs --actions-from-line.")
    if args.actions_from_line:
        options["actions_from_line"] = (
            LINE_ACTIONS if args.action_count is None else args.action_count
        )
    if args.steering_range is not None:
        options["steering_range"] = parse_range(
            args.steering_range, "--steering-range", -MAX_STEERING, MAX_STEERING, "degrees"
        )
    if args.speed_range is not None:
        options["speed_range"] = parse_range(
            args.speed_range, "--speed-range", MIN_SPEED, MAX_SPEED, "m/s"
        )
    if args.hp:
        options["hyperparameters"] = parse_hp_assignments(args.hp)
    if args.camera_randomisation is not None:
        try:
            chosen = parse_camera_randomisation(args.camera_randomisation)
        except ValueError as error:
            raise ModelError(f"--camera-randomisation: {error}") from None
        options["camera_randomisation"] = chosen
    if args.race_type is not None:
        options["race_type"] = args.race_type.strip().lower()
    if args.obstacles is not None:
        options["obstacles"] = args.obstacles
    if args.randomize_obstacles:
        options["randomize_obstacles"] = True
    if args.bots is not None:
        options["bots"] = args.bots
    if args.bot_speed is not None:
        options["bot_speed"] = args.bot_speed
    if args.bot_lane_change:
        options["bot_lane_change"] = True
    return {key: value for key, value in options.items() if value is not None}


def _new(args: argparse.Namespace) -> int:

    folder = new_model(args.name, **_spec_options(args))
    return _created(folder, f"Created model {folder.name}", args.json, [])


def _clone(args: argparse.Namespace) -> int:

    source = open_model(args.source)
    folder = clone_model(source, args.name, **_spec_options(args))
    notes = []
    if folder.has_policy():
        notes.append(f"training continues from {source.name}'s trained policy.")
    return _created(folder, f"Cloned {source.name} as {folder.name}", args.json, notes)


def _created(folder: ModelFolder, title: str, as_json: bool, notes: list[str]) -> int:
    row = model_row(folder)
    if as_json:
        print_json({**row, "path": str(folder.path), "notes": notes})
        return 0
    table = Table(title=Text(title), show_header=False)
    table.add_column("what")
    table.add_column("value")
    for key in ("track", "sensor", "actions"):
        table.add_row(key, Text(str(row[key])))
    table.add_row("folder", Text(str(folder.path)))
    print_table(table)
    for note in notes:
        print(f"Note: {note}")
    # A car archive drives as it is; everything else learns first.
    step = "evaluate" if folder.has_car_archive() else "train"
    print(f"Next: racer-tui {step} {folder.name}")
    return 0


# --- list and show ---------------------------------------------------------------------------


def _list(as_json: bool) -> int:
    rows = [model_row(folder) for folder in list_models()]
    if as_json:
        print_json(rows)
        return 0
    if not rows:
        print("No models yet; create one with `racer-tui model new NAME`.")
        return 0
    table = Table(title="Models")
    for column in ("name", "status", "track", "sensor", "actions"):
        table.add_column(column, no_wrap=column != "actions")
    table.add_column("best lap", justify="right", no_wrap=True)
    for row in rows:
        # A race type other than the time trial under the track (`model show` says its
        # boxes or bots): a column of its own does not fit 80 columns.
        track = Text(row["track"] or "-")
        race = (row["race"] or "time trial").split(",")[0]
        if race != "time trial":
            track.append(f"\n{race}", style="dim")
        table.add_row(
            Text(row["name"]),
            Text(row["status"]),
            track,
            Text(row["sensor"] or "-"),
            Text(row["actions"] or row.get("problem", "-")),
            _seconds(row["best_lap_s"]),
        )
    print_table(table)
    return 0


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f} s"


def _show(name: str, as_json: bool) -> int:
    details = model_details(open_model(name))
    if as_json:
        print_json(details)
        return 0
    facts = Table(title=Text(f"Model {details['name']}"), show_header=False)
    facts.add_column("what")
    facts.add_column("value")
    metadata = details["metadata"]
    for label, value in (
        ("status", details["status"]),
        ("track", details["track"]),
        ("race", details["race"]),
        ("sensor", details["sensor"]),
        ("actions", details["actions_summary"]),
        ("network", network_words(metadata)),
        ("algorithm", metadata["training_algorithm"]),
        *(
            [("drives with", "a DeepRacer car archive, never trained here")]
            if details["car_archive"]
            else [("reward function", details["reward_function"])]
        ),
        *(
            [("camera randomisation", details["camera_randomisation"])]
            if "camera" in details["sensor"].split("+")
            else []
        ),
        *([("car", details["car_look"])] if details["car_look"] else []),
        ("time limit", f"{details['max_minutes']:g} min"),
        ("content hash", details["content_hash"][:16]),
        ("folder", details["path"]),
        *details["notes"].items(),
        *([("physics", details["physics_note"])] if details["physics_note"] else []),
    ):
        facts.add_row(label, Text(str(value)))
    print_table(facts)
    if details["car_refusal"] is None:
        print_table(car_table(metadata["action_space_type"], details["on_the_car"]))
    else:
        if details["actions"]:
            actions = Table(title="Action space")
            for column in ("#", "steering (deg)", "speed (m/s)"):
                actions.add_column(column, justify="right")
            for action in details["actions"]:
                actions.add_row(
                    str(action["index"]),
                    f"{action['steering_angle']:.1f}",
                    f"{action['speed']:.2f}",
                )
            print_table(actions)
        print(f"A DeepRacer car cannot run this model: {details['car_refusal']}.")
    print_table(_key_values("Hyperparameters", details["hyperparameters"]))
    print_table(_training_table(details["training"]))
    for evaluation in details["evaluations"]:
        print_table(_evaluation_table(evaluation))
    return 0


def _key_values(title: str, values: dict[str, Any]) -> Table:
    table = Table(title=title, show_header=False)
    table.add_column("key")
    table.add_column("value")
    for key, value in values.items():
        table.add_row(key, Text("-" if value is None else f"{value}"))
    return table


# `model show`'s words for the training summary's keys (the JSON keeps the keys); a fact
# with nothing to say (no failure, no state yet) is left out.
TRAINING_LABELS = {
    "episodes": "episodes",
    "laps_completed": "laps completed",
    "best_progress": "best progress (%)",
    "recent_progress": "recent progress (%)",
    "recent_reward": "recent reward",
    "training_seconds": "training time (s)",
    "steps": "steps",
    "state": "state",
    "updated_at": "updated",
    "message": "last message",
    "problem": "problem",
    "physics": "car it learnt",
    "numerics": "trained in",
}


def _training_table(values: dict[str, Any]) -> Table:
    table = Table(title="Training", show_header=False)
    table.add_column("key")
    table.add_column("value")
    for key, value in values.items():
        if value is None or value == "" or key not in TRAINING_LABELS:
            continue
        table.add_row(TRAINING_LABELS[key], Text(f"{value}"))
    return table


def _evaluation_table(evaluation: dict[str, Any]) -> Table:
    """Like the DeepRacer console: trial, time, % track completed, status."""
    table = Table(title=Text(f"Evaluation {evaluation['file']}"))
    for column in ("trial", "time", "completed", "status", "off-track"):
        table.add_column(column, justify="right" if column != "status" else "left")
    for trial in evaluation["trials"]:
        table.add_row(
            str(trial["trial"]),
            f"{trial['elapsed_time_in_milliseconds'] / 1000:.3f} s",
            f"{trial['completion_percentage']:g}%",
            Text(trial["episode_status"]),
            str(trial["off_track_count"]),
        )
    if "problem" in evaluation:
        table.caption = evaluation["problem"]
    return table


# --- delete, import, export ------------------------------------------------------------------


def _delete(name: str, yes: bool) -> int:
    folder = open_model(name)
    if not yes:
        if not sys.stdin.isatty():
            raise ModelError(
                f"not deleting {folder.name!r} without asking; add --yes to delete it anyway."
            )
        answer = input(f"Delete model {folder.name} ({folder.path})? [y/N] ")
        if answer.strip().lower() not in ("y", "yes"):
            print("Kept it.")
            return 1
    delete_model(folder)
    print(f"Deleted model {folder.name}.")
    return 0


def _import(args: argparse.Namespace) -> int:

    result = import_model(
        Path(args.path), name=args.name, track=args.track, untrained=args.untrained
    )
    if args.json:
        print_json(
            {**model_row(result.folder), "path": str(result.folder.path), "notes": result.notes}
        )
        return 0
    return _created(
        result.folder, f"Imported {args.path} as {result.folder.name}", False, list(result.notes)
    )


def _export(name: str, output: str | None, *, replace: bool, as_json: bool) -> int:

    folder = open_model(name)
    out = export_target(Path(output), folder.name) if output else Path(folder.name)
    written = export_bundle(folder, out, replace=replace)
    notes = export_notes(folder.metadata())
    if as_json:
        print_json({"name": folder.name, "format": "bundle", "path": str(written), "notes": notes})
        return 0
    print(f"Exported {folder.name} to {written}")
    for note in notes:
        print(f"Note: {note}")
    return 0


def _act(name: str, picture: Path, *, as_json: bool) -> int:

    rgb = read_picture(picture)
    archive = Path(name).expanduser()
    if is_car_archive_name(archive):
        if not archive.is_file():
            raise CarModelError(f"{archive}: the file does not exist; give a car archive.")
        result, label = archive_answer(archive, rgb), archive.name
    else:
        folder = open_model(name)
        result, label = model_answer(folder.path, rgb), folder.name
    if as_json:
        print_json({"model": label, "picture": str(picture), **asdict(result)})
        return 0
    width, height = result.frame_size
    chosen = result.action
    if result.kind == "discrete":
        table = Table(title=Text(f"{label} on {picture.name} ({width}x{height} grey, raw 0..255)"))
        for column in ("#", "probability", "steering (deg)", "speed (m/s)", "car steering"):
            table.add_column(column, justify="right")
        for action, probability in zip(result.actions, result.outputs, strict=True):
            mark = " <" if action.index == chosen.index else ""
            table.add_row(
                f"{action.index}{mark}",
                f"{probability:.4f}",
                f"{action.steering_angle:.1f}",
                f"{action.speed:.2f}",
                _steering_words(action.steering),
            )
        print_table(table)
    else:
        steer, speed = result.outputs
        print(f"{label} on {picture.name} ({width}x{height} grey): mean {steer:+.4f} {speed:+.4f}")
    what = f"action {chosen.index}: " if chosen.index is not None else ""
    print(
        f"The car takes {what}{chosen.steering_angle:.1f} deg at {chosen.speed:.2f} m/s, "
        f"steering {_steering_words(chosen.steering)} at {chosen.throttle:.0%} throttle."
    )
    return 0


def _export_car(name: str, output: str | None, *, replace: bool, as_json: bool) -> int:

    from sim.car_export.export import export_car_archive  # noqa: PLC0415 (torch: only for an export)

    folder = open_model(name)
    out = export_target(Path(output), folder.name) if output else Path(folder.name)
    written = export_car_archive(folder, out, replace=replace)
    if as_json:
        print_json(
            {
                "name": folder.name,
                "format": "car",
                "path": str(written.path),
                "on_the_car": [asdict(action) for action in written.actions],
                "notes": list(written.notes),
            }
        )
        return 0
    print(f"Exported {folder.name} for a DeepRacer car to {written.path}")
    print_table(car_table(written.metadata.action_space.kind, [asdict(a) for a in written.actions]))
    print(
        "Upload it on the car's web page (Models, Upload). The car steers each action as a "
        "share of its calibrated steering lock and throttles it as a share of its max-speed "
        "setting."
    )
    for note in written.notes:
        print(f"Note: {note}")
    return 0


def car_table(kind: str, rows: list[dict[str, Any]]) -> Table:
    """The action space as a DeepRacer car drives it (`sim.car_archive.car_mapping`)."""
    table = Table(title="On a DeepRacer car")
    columns = ("#", "steering (deg)", "speed (m/s)", "car steering", "car throttle")
    for column in columns if kind == "discrete" else columns[1:]:
        table.add_column(column, justify="right")
    for row in rows:
        cells = [
            f"{row['steering_angle']:.1f}",
            f"{row['speed']:.2f}",
            _steering_words(row["steering"]),
            f"{row['throttle']:.0%}",
        ]
        table.add_row(*([str(row["index"])] if kind == "discrete" else []), *cells)
    table.caption = "car steering: share of its steering lock; throttle: of its max-speed setting"
    return table


def _steering_words(share: float) -> str:
    if abs(share) < 0.005:
        return "straight"
    return f"{abs(share):.0%} {'left' if share > 0 else 'right'}"

"""`racer-tui sync`: share the league through a store (a shared folder, or DynamoDB + S3).

    racer-tui sync init STORE [--bundles s3://BUCKET/PREFIX]   the organiser, once
    racer-tui sync set STORE [--bundles s3://BUCKET/PREFIX]    each racer, once per league
    racer-tui sync [--push | --pull] [--store URL] [--json]    push what is new, pull the rest
    racer-tui sync status [--json]                             what sync set aside, and why
    racer-tui sync fetch-bundle HASH [--name NAME]             install a racer's model
    racer-tui sync verify [--again] [--json]                   re-run races, compare laps

Every command takes `--db FILE`. Text from other racers (names, reasons, excerpts) is
printed as plain text: with print(), or in rich tables as Text cells, never as markup.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    Parsers = argparse._SubParsersAction[argparse.ArgumentParser]

NAMES = ("sync",)


def register(commands: Parsers) -> None:
    sync = commands.add_parser(
        "sync",
        help="share the league through a shared folder or DynamoDB",
        description="With no ACTION: push this league's new records to its store, then pull "
        "everyone else's. Set the store once with `racer-tui sync set STORE`.",
    )
    direction = sync.add_mutually_exclusive_group()
    direction.add_argument("--push", action="store_true", help="only push")
    direction.add_argument("--pull", action="store_true", help="only pull")
    sync.add_argument(
        "--verify",
        action="store_true",
        help="then re-run the races not verified yet and withdraw any whose laps differ "
        "(as `racer-tui sync verify`)",
    )
    sync.add_argument("--store", metavar="URL", help="this store instead of the saved one")
    _common(sync, top=True, bundles=True, as_json=True)
    actions = sync.add_subparsers(dest="sync_command", metavar="ACTION")
    init = actions.add_parser(
        "init", help="create a store (the organiser, once)", description=_INIT_HELP
    )
    init.add_argument("url", metavar="STORE", help="dir:PATH or dynamodb://TABLE?region=R")
    init.add_argument("--bundles", metavar="S3URL", help="also create this bundle bucket")
    _common(init)
    use = actions.add_parser("set", help="save the store this league syncs with")
    use.add_argument("url", metavar="STORE", help="dir:PATH or dynamodb://TABLE?region=R")
    use.add_argument(
        "--organiser",
        metavar="FP",
        help="the organiser's key fingerprint, as they read it out: a store founded by "
        "any other key is refused",
    )
    _common(use, bundles=True)
    status = actions.add_parser("status", help="last syncs, conflicts, quarantined records")
    _common(status, as_json=True)
    verify = actions.add_parser(
        "verify",
        help="re-run the league's races and withdraw any whose laps differ",
        description="Run each race again from the model, track, rules and seed it names "
        "(races are deterministic) and compare its laps. A race that comes out differently "
        "leaves the leaderboard and is listed in quarantine; one that cannot be re-run here "
        "(its model is not in this garage: fetch it with `racer-tui sync fetch-bundle`; or it "
        "was timed by another physics or by hand) is unverifiable, and the leaderboard says "
        "so. Races verified before are not run again unless --again.",
    )
    verify.add_argument("--again", action="store_true", help="re-run races verified before")
    _common(verify, as_json=True)
    fetch = actions.add_parser("fetch-bundle", help="install a racer's model from the bundle store")
    fetch.add_argument("hash", metavar="HASH", help="model hash or bundle hash (8+ characters)")
    fetch.add_argument("--name", help="garage name to install it under")
    _common(fetch, bundles=True)


_INIT_HELP = (
    "Create the store: for dir:PATH the folder (its parent must exist) and its marker file; "
    "for dynamodb:// the table and its index (needs credentials allowed to create tables). "
    "This machine's signing key becomes the league's organiser key: only results signed by "
    "keys it admits (`racer-tui racer admit NAME`) reach anyone's leaderboard. "
    "Safe to run again."
)


def _common(
    parser: argparse.ArgumentParser,
    *,
    top: bool = False,
    bundles: bool = False,
    as_json: bool = False,
) -> None:
    # On the actions, SUPPRESS keeps a value given before the action (sync --db F status).
    default: Any = None if top else argparse.SUPPRESS
    parser.add_argument(
        "--db",
        type=Path,
        metavar="FILE",
        default=default,
        help="league database (default: league.db in the data dir)",
    )
    if bundles:
        parser.add_argument(
            "--bundles",
            metavar="S3URL",
            default=default,
            help="model bundles in s3://BUCKET/PREFIX (default: the saved one)",
        )
    if as_json:
        parser.add_argument(
            "--json",
            action="store_true",
            default=False if top else argparse.SUPPRESS,
            help="print JSON instead of text",
        )


def run(args: argparse.Namespace) -> int:
    # Imported when a sync runs, not for `--help` or the app's start: the league's modules
    # load SQLite with sqlite-utils (and pandas), and a store may load boto3.
    running = importlib.import_module(f"{__name__}.running")
    result: int = running.run(args)
    return result

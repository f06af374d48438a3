"""`racer-tui sync` run: each action on the opened league (the parsers are the package's)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict
from typing import Any

from rich import box
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn
from rich.progress import Progress as ProgressBar
from rich.table import Table
from rich.text import Text

from league.opening import open_league
from league.store import League
from league.sync import open_bundle_store, open_store
from league.sync.bundle_sync import fetch_bundle
from league.sync.engine import Progress, SyncSummary
from league.sync.errors import SyncError
from league.sync.local import BUNDLES_SETTING, get_setting
from league.sync.session import found_store, save_store, saved_store, sync_league
from league.sync.status import (
    differences,
    side_label,
    summary_details,
    summary_headline,
    sync_status,
)
from league.trust.head_to_head_replay import verify_head_to_heads
from league.trust.replay import OUTCOMES, Verdict, verify_races
from racer_tui.cli.output import print_json, print_table
from sim.foundation.plural import counted
from sim.training.drivers import DriversByHash

_EXCERPT = 60
_RUN_ORDER = (
    "pushed",
    "pulled",
    "skipped",
    "already_here",
    "aliased",
    "waiting",
    "conflicts",
    "quarantined",
    "refused",
)


def run(args: argparse.Namespace) -> int:
    action = getattr(args, "sync_command", None)

    handlers: dict[str | None, Callable[[League, argparse.Namespace], int]] = {
        None: _sync,
        "init": _init,
        "set": _set,
        "status": _status,
        "fetch-bundle": _fetch,
        "verify": _verify,
    }
    with open_league(args.db) as league:
        return handlers[action](league, args)


# --- init and set ------------------------------------------------------------------------------


def _init(league: League, args: argparse.Namespace) -> int:

    with open_store(args.url) as store:
        store.init()
        print(f"Store ready: {store.description}.")
        founding = found_store(league, store, args.url)
    print(founding)
    if args.bundles:
        with open_bundle_store(args.bundles) as bundles:
            bundles.init()
            print(f"Bundle store ready: {bundles.description}.")
    suffix = f" --bundles {args.bundles}" if args.bundles else ""
    print(f"Each racer now runs: racer-tui sync set {args.url}{suffix}")
    print("When they have synced once, admit each one: racer-tui racer admit NAME")
    return 0


def _set(league: League, args: argparse.Namespace) -> int:

    store, bundles = save_store(league, args.url, args.bundles, organiser=args.organiser)
    print(f"This league syncs with {store}" + (f", bundles in {bundles}" if bundles else "") + ".")
    print("Run `racer-tui sync` to push and pull.")
    return 0


# --- sync ----------------------------------------------------------------------------------------


def _sync(league: League, args: argparse.Namespace) -> int:

    url = saved_store(league, args.store)
    with _progress(not args.json and sys.stderr.isatty()) as progress:
        summary, notes = sync_league(
            league,
            url,
            bundles_url=args.bundles,
            push_records=not args.pull,
            pull_records=not args.push,
            progress=progress,
        )
    verdicts = _verdicts(league, again=False) if args.verify else None
    if args.json:
        replays = {} if verdicts is None else {"verified": [asdict(v) for v in verdicts]}
        print_json({**summary.to_json(), "notes": notes, **replays})
        return 0
    _print_summary(summary, notes)
    if verdicts is not None:
        _print_verdicts(verdicts)
    return 0


@contextmanager
def _progress(enabled: bool) -> Iterator[Progress | None]:
    """A progress bar per direction on stderr (a terminal only; scripts get none)."""
    if not enabled:
        yield None
        return

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn())
    with ProgressBar(*columns, console=Console(stderr=True), transient=True) as bar:
        tasks: dict[str, Any] = {}

        def update(direction: str, done: int, total: int | None) -> None:
            if direction not in tasks:
                tasks[direction] = bar.add_task(f"{direction}ing", total=total)
            bar.update(tasks[direction], completed=done, total=total)

        yield update


def _print_summary(summary: SyncSummary, notes: list[str]) -> None:

    print(summary_headline(summary))
    for line in summary_details(summary, notes):
        print(f"  {line}")  # plain print: store text is never markup
    if summary.conflicts:
        print("Both sides of each conflict are kept: see `racer-tui sync status`.")
    elif summary.quarantined:
        print("Quarantined records reach no leaderboard: see `racer-tui sync status`.")


# --- status ------------------------------------------------------------------------------------


def _status(league: League, args: argparse.Namespace) -> int:

    document = sync_status(league).to_json()
    if getattr(args, "json", False):
        print_json(document)
        return 0
    _print_status(document)
    return 0


def _print_status(document: dict[str, Any]) -> None:
    if document["store"] is None:
        print("No store set: run `racer-tui sync set STORE` (for example dir:/mnt/league-share).")
    else:
        print(f"Store: {document['store']}")
        if document["bundles"]:
            print(f"Bundles: {document['bundles']}")
        failure = document.get("last_failure")
        if failure:
            print(f"The last sync failed at {failure['at']}: {failure['message']}")
        for direction in ("push", "pull"):
            run = document["runs"].get(direction)
            if run is None:
                print(f"Last {direction}: never")
            else:
                figures = run["summary"]
                counts = ", ".join(
                    f"{name.replace('_', ' ')} {figures[name]}"
                    for name in _RUN_ORDER
                    if name in figures
                )
                print(f"Last {direction}: {run['finished_at']} ({counts})")
        print(
            f"Records the store holds from or for this league: {document['in_store']}; "
            f"new here, not pushed yet: {document['to_push']}."
        )
    if document["waiting"]:
        print(f"Waiting for records they refer to: {len(document['waiting'])}")
        for row in document["waiting"]:
            print(f"  {row['kind']} {row['record_id']}: needs {row['waiting_for']}")
    if document["aliases"]:
        print(f"Made on two machines, kept as aliases: {len(document['aliases'])}")
        for row in document["aliases"]:
            print(f"  {row['kind']} {row['record_id']} -> {row['canonical_id']}")
    print(f"Bundles known: {len(document['bundles_known'])}")
    _conflict_table(document["conflicts"])
    _quarantine_table(document["quarantined"])


def _conflict_table(rows: list[dict[str, Any]]) -> None:

    if not rows:
        print("Conflicts: none.")
        return
    table = Table(title=Text(f"Conflicts ({len(rows)}): both sides kept"), box=box.SIMPLE_HEAD)
    for title in ("record", "what", "here", "in the store"):
        table.add_column(title, overflow="fold")
    for row in rows:
        here, there = differences(row["local_body"], row["remote_body"])
        table.add_row(
            Text(f"{row['kind']} {row['record_id']}"),
            Text(row["detail"]),
            Text(side_label(row["local_hash"], row["local_version"], here)),
            Text(side_label(row["remote_hash"], row["remote_version"], there)),
        )
    print_table(table)


def _quarantine_table(rows: list[dict[str, Any]]) -> None:
    if not rows:
        print("Quarantined: none.")
        return
    table = Table(title=Text(f"Quarantined ({len(rows)}): not added"), box=box.SIMPLE_HEAD)
    for title in ("where", "kind", "id", "reason", "excerpt"):
        table.add_column(title, overflow="fold")
    for row in rows:
        table.add_row(
            Text(row["location"]),
            Text(row["kind"] or "?"),
            Text(row["record_id"] or "?"),
            Text(row["reason"]),
            Text(row["excerpt"][:_EXCERPT]),
        )
    print_table(table)


# --- bundles -----------------------------------------------------------------------------------


def _fetch(league: League, args: argparse.Namespace) -> int:

    url = getattr(args, "bundles", None) or get_setting(league, BUNDLES_SETTING)
    if url is None:
        raise SyncError(
            "no bundle store is set: pass --bundles s3://BUCKET/PREFIX or save one with "
            "`racer-tui sync set STORE --bundles s3://BUCKET/PREFIX`"
        )
    with open_bundle_store(url) as store:
        installed = fetch_bundle(league, store, args.hash, getattr(args, "name", None))
    print(
        f"Installed model {installed.name} (model {installed.bundle.model_hash[:12]}, "
        f"bundle {installed.bundle.sha256[:12]})."
    )
    for note in installed.notes:
        print(f"  {note}")
    return 0


def _verify(league: League, args: argparse.Namespace) -> int:
    verdicts = _verdicts(league, again=args.again)
    if args.json:
        print_json([asdict(verdict) for verdict in verdicts])
    else:
        _print_verdicts(verdicts)
    return 0


def _verdicts(league: League, *, again: bool) -> list[Verdict]:

    drivers = DriversByHash()  # one garage, hashed once, for both kinds of race
    return [
        *verify_races(league, drivers, again=again),
        *verify_head_to_heads(league, drivers, again=again),
    ]


def _print_verdicts(verdicts: list[Verdict]) -> None:

    counts = {outcome: sum(v.outcome == outcome for v in verdicts) for outcome in OUTCOMES}
    print(
        f"Re-ran {counted(len(verdicts) - counts['unverifiable'], 'race')}: {counts['same']} "
        f"the same, {counts['differs']} different (withdrawn, see `racer-tui sync status`); "
        f"{counts['unverifiable']} unverifiable here."
    )
    for verdict in verdicts:
        if verdict.outcome != "same":
            # Racer names come from other machines: printed, never rendered as markup.
            print(
                f"  {verdict.outcome}: race {verdict.race_id} ({verdict.racer}): {verdict.detail}"
            )

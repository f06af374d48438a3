"""Sync benchmark: push and pull a big league through each store, and push it twice.

    python -m benchmarks.league.sync [--json] [--records 10000] [--laps 5] [--stores dir,dynamodb]

For each store: fill a league with `--records` submissions (each with `--laps` laps, by
100 racers on 3 tracks, plus a small season of closed nights with races), push it all
(timed), push again (it must send nothing: the figures say how many records it
considered and wrote), then pull everything into a second, empty league (timed) and
check that both leagues print the same leaderboard. The DynamoDB store runs against a
moto server this script starts on a free loopback port (in its own process, as a real
server would be) and stops at the end. Figures are printed, never judged: the targets
are in the issue (10,000 submissions each way in at most 30 s on loopback DynamoDB and
10 s with the shared folder), and the machine's load moves them.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import psutil

from benchmarks.league.board import fill
from league.leaderboard import Filters, leaderboard
from league.opening import open_league
from league.records import SHARED_TABLES
from league.store import League
from league.sync.engine import pull, push, store_key
from league.sync.outgoing import count_unsent
from league.sync.stores import open_store
from league.trust.keys import SigningKey
from league.trust.membership import found_league

TARGETS_S = {"dir": 10.0, "dynamodb": 30.0}


@dataclass
class Server:
    endpoint: str
    pid: int | None = None  # the server process, whose CPU time is reported

    def cpu_seconds(self) -> float:
        if self.pid is None:
            return 0.0
        times = psutil.Process(self.pid).cpu_times()
        return float(times.user + times.system)


@contextlib.contextmanager
def moto_server() -> Iterator[Server]:
    """A moto server on 127.0.0.1 in a child process."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = subprocess.Popen(
        [sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 30
        while True:
            with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
                break
            if server.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("the moto server did not start (is moto[server] installed?)")
            time.sleep(0.05)
        yield Server(f"http://127.0.0.1:{port}", server.pid)
    finally:
        server.terminate()
        server.wait(timeout=10)


def _board(league: League) -> list[tuple[Any, ...]]:
    return [
        (row.track_name, row.rank, row.racer, row.display_name, row.record_id, row.score)
        for row in leaderboard(league, Filters())
    ]


def _shared_records(league: League) -> int:
    total = 0
    for table in SHARED_TABLES:
        row = league.query_one(f"SELECT count(*) FROM {table}")
        total += int(row[0]) if row else 0
    return total


class _Clock:
    """Wall time, this process's CPU time and the server's, around one step."""

    def __init__(self, server: Server) -> None:
        self.server = server

    @contextlib.contextmanager
    def measure(self, into: dict[str, float]) -> Iterator[None]:
        wall, cpu, server = time.perf_counter(), time.process_time(), self.server.cpu_seconds()
        yield
        into["wall"] = time.perf_counter() - wall
        into["cpu"] = time.process_time() - cpu
        into["server_cpu"] = self.server.cpu_seconds() - server


def bench_store(
    url: str, root: Path, args: argparse.Namespace, server: Server | None = None
) -> dict[str, Any]:
    key = store_key(url)
    with open_league(root / "source.db") as source, open_league(root / "copy.db") as copy:
        fill(
            source,
            racers=100,
            submissions=args.records,
            laps_per_submission=args.laps,
            tracks=3,
            nights=2,
            racers_per_night=10,
        )
        # The source league is the organiser's: its key founds the league, so the copy
        # accepts every record it signs. A key of its own: the bench never touches the
        # racer's data directory.
        signing = SigningKey.generate()
        found_league(source, signing)
        records = _shared_records(source)
        clock = _Clock(server or Server(""))
        timed: dict[str, dict[str, float]] = {"push": {}, "again": {}, "pull": {}}
        with open_store(url) as store:
            store.init()
            with clock.measure(timed["push"]):
                pushed = push(source, store, key, signing_key=signing)
            considered = count_unsent(source, key)
            with clock.measure(timed["again"]):
                again = push(source, store, key, signing_key=signing)
        # A fresh connection, as another racer would have.
        with open_store(url) as store, clock.measure(timed["pull"]):
            pulled = pull(copy, store, key)
        same_board = _board(source) == _board(copy)
    push_s, pull_s = timed["push"]["wall"], timed["pull"]["wall"]
    return {
        "store": url.split(":", 1)[0],
        "records": records,
        "submissions": args.records,
        "laps_per_submission": args.laps,
        "push_seconds": round(push_s, 2),
        "push_cpu_seconds": round(timed["push"]["cpu"], 2),
        "push_server_cpu_seconds": round(timed["push"]["server_cpu"], 2),
        "push_records_per_second": round(pushed.pushed / push_s) if push_s else None,
        "pushed": pushed.pushed,
        "second_push_considered": considered,
        "second_push_pushed": again.pushed,
        "second_push_seconds": round(timed["again"]["wall"], 3),
        "pull_seconds": round(pull_s, 2),
        "pull_cpu_seconds": round(timed["pull"]["cpu"], 2),
        "pull_server_cpu_seconds": round(timed["pull"]["server_cpu"], 2),
        "pull_records_per_second": round(pulled.pulled / pull_s) if pull_s else None,
        "pulled": pulled.pulled,
        "same_leaderboard": same_board,
        "target_seconds_each_way": TARGETS_S[url.split(":", 1)[0]],
        "load_average": round(os.getloadavg()[0], 1),
    }


def run(args: argparse.Namespace) -> list[dict[str, Any]]:
    results = []
    stores = [name.strip() for name in args.stores.split(",") if name.strip()]
    for name in stores:
        with tempfile.TemporaryDirectory(prefix="sync-bench-") as tmp:
            root = Path(tmp)
            if name == "dir":
                results.append(bench_store(f"dir:{root / 'shared'}", root, args))
            elif name == "dynamodb":
                with _dummy_aws(), moto_server() as server:
                    table = f"bench-{uuid.uuid4().hex[:8]}"
                    url = f"dynamodb://{table}?region=us-east-1&endpoint={server.endpoint}"
                    results.append(bench_store(url, root, args, server))
            else:
                raise SystemExit(f"unknown store {name!r}: choose dir and/or dynamodb")
    return results


@contextlib.contextmanager
def _dummy_aws() -> Iterator[None]:
    """Credentials for the local server only; the real AWS configuration is never read."""
    names = {
        "AWS_ACCESS_KEY_ID": "bench",
        "AWS_SECRET_ACCESS_KEY": "bench",
        "AWS_CONFIG_FILE": os.devnull,
        "AWS_SHARED_CREDENTIALS_FILE": os.devnull,
        "AWS_EC2_METADATA_DISABLED": "true",
    }
    saved = {name: os.environ.get(name) for name in (*names, "AWS_PROFILE", "AWS_SESSION_TOKEN")}
    os.environ.update(names)
    os.environ.pop("AWS_PROFILE", None)
    os.environ.pop("AWS_SESSION_TOKEN", None)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.league.sync", description=__doc__)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--records", type=int, default=10_000, help="submissions to sync")
    parser.add_argument("--laps", type=int, default=5, help="laps per submission")
    parser.add_argument("--stores", default="dir,dynamodb", help="dir, dynamodb or both")
    args = parser.parse_args(argv)
    results = run(args)
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    lines = [
        f"{'store':<10}{'records':>9}{'push s':>8}{'rec/s':>7}{'cpu s':>7}{'server':>8}"
        f"{'pull s':>8}{'rec/s':>7}{'cpu s':>7}{'server':>8}{'target':>8}  second push",
    ]
    for r in results:
        lines.append(
            f"{r['store']:<10}{r['records']:>9,}{r['push_seconds']:>8.2f}"
            f"{r['push_records_per_second']:>7,}{r['push_cpu_seconds']:>7.1f}"
            f"{r['push_server_cpu_seconds']:>8.1f}{r['pull_seconds']:>8.2f}"
            f"{r['pull_records_per_second']:>7,}{r['pull_cpu_seconds']:>7.1f}"
            f"{r['pull_server_cpu_seconds']:>8.1f}{r['target_seconds_each_way']:>8.0f}  "
            f"{r['second_push_considered']} to send, {r['second_push_pushed']} written "
            f"({r['second_push_seconds']} s)"
            + ("" if r["same_leaderboard"] else "  LEADERBOARDS DIFFER")
        )
    lines.append(
        f"(cpu s: this process; server: the moto server process; load average "
        f"{results[-1]['load_average'] if results else '?'} on {os.cpu_count()} cores)"
    )
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

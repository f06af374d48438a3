"""The live page under load: many viewers of `/live` while a physical heat is timed.

    python -m benchmarks.web.live_load [--viewers 200] [--keys 240] [--json]

Starts `racer-tui serve` as a host does (a child process on loopback) over a fresh league
with one night, connects `--viewers` clients to the live page's event stream (in a child
process of their own, as viewers are other machines: they do not share this process's
interpreter with the app), and then drives the real app's timekeeper on that night's
heats through Pilot, as `benchmarks.app.timekeeper` does: `--keys` presses alternating
Car Reset and Capture Lap, each heat written for the projector and the web pages as a
night's heat is.

Figures:
- the timekeeper's key latency (p50 / p95 / max), from the press to the screen update
  showing its effect;
- how far the viewers are behind: from each Capture Lap key to the moment each viewer's
  stream shows the new lap (p50 / p95 / max over every viewer and lap), and how many laps
  a viewer never saw because the next heat replaced the heat first (a heat's last lap,
  when the next heat opens within one poll of the live file);
- the server's CPU over the keys, as a share of one core, and its resident memory when
  the viewers had connected and at the end;
- viewers connected and events each received.

Targets (issue 45), printed beside the figures and never the exit code: key p95 under
50 ms, the server under a quarter of a core, its memory flat; and (the page's own
promise) viewers within 250 ms of the app. Exit 1 with one sentence when it cannot run.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import psutil

from benchmarks.app.soak import SoakError, percentiles

DEFAULT_VIEWERS = 200
DEFAULT_KEYS = 240
CONNECT_SECONDS = 60.0
SEEN_SECONDS = 15.0  # for the viewers to see the last laps captured
TARGET_KEY_P95_MS = 50.0
TARGET_SERVER_CORE = 0.25
TARGET_BEHIND_MS = 250.0


# --- the viewers (a child process) ---------------------------------------------------------


async def _viewer(host: str, port: int, path: str, seen: list[tuple[int, float]]) -> int:
    """One viewer: reads the event stream, noting when each new lap count first shows;
    returns how many events it received."""
    reader, writer = await asyncio.open_connection(host, port)
    writer.write(
        f"GET {path} HTTP/1.1\r\nHost: {host}\r\nAccept: text/event-stream\r\n\r\n".encode()
    )
    await writer.drain()
    events = 0
    laps_shown = -1
    try:
        while line := await reader.readline():
            if not line.startswith(b"data: "):
                continue  # headers, chunk sizes, blank lines, comments
            events += 1
            heat = json.loads(line[6:])["heat"]
            laps = len(heat["laps"]) if heat else 0
            if laps != laps_shown:
                seen.append((laps, time.time()))
                laps_shown = laps
    except (ConnectionError, asyncio.CancelledError):
        pass
    finally:
        writer.close()
    return events


async def _viewers(host: str, port: int, path: str, count: int) -> dict[str, Any]:
    seens: list[list[tuple[int, float]]] = [[] for _ in range(count)]
    tasks = [asyncio.create_task(_viewer(host, port, path, seen)) for seen in seens]
    deadline = time.monotonic() + CONNECT_SECONDS
    while sum(1 for seen in seens if seen) < count and time.monotonic() < deadline:
        await asyncio.sleep(0.05)  # every viewer has its first event
    print(json.dumps({"ready": sum(1 for seen in seens if seen)}), flush=True)
    # Until the benchmark sends the laps it captured: then until every viewer has seen
    # them (a lap captured by the last key is still on its way), for at most a while.
    line = await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)
    captured = [(int(laps), float(at)) for laps, at in json.loads(line or "[]")]
    deadline = time.monotonic() + SEEN_SECONDS
    while time.monotonic() < deadline and not all(
        _accounted(captured, seen) == len(captured) for seen in seens
    ):
        await asyncio.sleep(0.05)
    for task in tasks:
        task.cancel()
    events = await asyncio.gather(*tasks, return_exceptions=True)
    return {"seen": seens, "events": [e if isinstance(e, int) else 0 for e in events]}


def viewers_child(url: str, count: int) -> int:
    found = re.match(r"http://([^:/]+):(\d+)(/.*)", url)
    assert found, url
    host, port, path = found.group(1), int(found.group(2)), found.group(3)
    print(json.dumps(asyncio.run(_viewers(host, port, path, count))), flush=True)
    return 0


# --- the benchmark ---------------------------------------------------------------------------


def _prepare() -> str:
    """A league with one night, in the data home of RACER_TUI_HOME; its id."""
    from league.nights import new_night
    from league.opening import open_league
    from sim.garage.options import new_model
    from sim.tracks.catalog import DEFAULT_TRACK, resolve_track

    new_model("bench")
    with open_league() as league:
        return new_night(league, resolve_track(DEFAULT_TRACK), name="load night").id


def _start_server() -> tuple[subprocess.Popen[str], str]:
    server = subprocess.Popen(
        [sys.executable, "-m", "racer_tui.cli.main", "serve", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env={**os.environ},
    )
    assert server.stdout is not None
    first = server.stdout.readline()
    found = re.search(r"http://[^ ]+/", first)
    if found is None:
        server.kill()
        raise SoakError("racer-tui serve did not say where it listens")
    return server, found.group(0).rstrip("/")


def run(viewers: int, keys: int) -> dict[str, Any]:
    from benchmarks.app.timekeeper import press_keys

    night_id = _prepare()
    server, base = _start_server()
    crowd: subprocess.Popen[str] | None = None
    try:
        crowd = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "benchmarks.web.live_load",
                "--viewers-child",
                f"{base}/api/live/stream?id={night_id}",
                "--viewers",
                str(viewers),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert crowd.stdout is not None and crowd.stdin is not None
        ready = json.loads(crowd.stdout.readline() or "{}").get("ready", 0)
        if ready < viewers:
            raise SoakError(f"only {ready} of {viewers} viewers connected within 60 s")
        watched = psutil.Process(server.pid)
        rss_connected = watched.memory_info().rss / 1e6
        cpu_before, wall_before = watched.cpu_times(), time.perf_counter()
        captured: list[tuple[int, float]] = []
        latencies = asyncio.run(
            press_keys(keys, night_id=night_id, lap_captured=lambda n, at: captured.append((n, at)))
        )
        cpu_after, wall = watched.cpu_times(), time.perf_counter() - wall_before
        rss_end = watched.memory_info().rss / 1e6
        crowd.stdin.write(json.dumps(captured) + "\n")
        crowd.stdin.close()
        result = json.loads(crowd.stdout.readline() or "{}")
    finally:
        if crowd is not None and crowd.poll() is None:
            crowd.kill()
        server.terminate()
        server.wait(10)
    cpu = (cpu_after.user - cpu_before.user) + (cpu_after.system - cpu_before.system)
    return {
        "viewers": viewers,
        "keys": keys,
        "key_latency_ms": percentiles(latencies),
        "viewers_behind_ms": percentiles(_behind(captured, result.get("seen", []))),
        "laps_superseded": sum(
            len(_sightings(captured, seen)[1]) for seen in result.get("seen", [])
        ),
        "server_core_share": round(cpu / wall, 3),
        "server_rss_mb": {"viewers_connected": round(rss_connected, 1), "end": round(rss_end, 1)},
        "events_per_viewer": percentiles([float(e) for e in result.get("events", [])]),
        "seconds": round(wall, 1),
    }


def _behind(captured: list[tuple[int, float]], seens: list[list[list[float]]]) -> list[float]:
    """For each Capture Lap key and each viewer: how long until that viewer saw the lap."""
    return [delay for seen in seens for delay in _sightings(captured, seen)[0]]


def _accounted(captured: list[tuple[int, float]], seen: Sequence[Sequence[float]]) -> int:
    """How many of the captured laps one viewer has seen or will never see."""
    delays, superseded = _sightings(captured, seen)
    return len(delays) + len(superseded)


def _sightings(
    captured: list[tuple[int, float]], seen: Sequence[Sequence[float]]
) -> tuple[list[float], list[int]]:
    """For one viewer: how long after each Capture Lap key it saw the lap, and the laps it
    never saw because the stream had moved on to the next heat first (a heat's last lap,
    ended and replaced by the next heat within one poll of the file: the night's standings
    show it). A heat's lap counts start again at each new heat, so each key is matched
    with the first sighting of its count after it."""
    delays: list[float] = []
    superseded: list[int] = []
    sightings = sorted((at, int(laps)) for laps, at in seen)
    for laps, pressed in captured:
        shown = next((at for at, n in sightings if n == laps and at >= pressed), None)
        if shown is not None:
            delays.append((shown - pressed) * 1000.0)
        elif any(n < laps and at >= pressed for at, n in sightings):
            superseded.append(laps)
    return delays, superseded


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--viewers", type=int, default=DEFAULT_VIEWERS)
    parser.add_argument("--keys", type=int, default=DEFAULT_KEYS)
    parser.add_argument("--json", action="store_true", help="one JSON object")
    parser.add_argument("--viewers-child", metavar="URL", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.viewers_child:
        return viewers_child(args.viewers_child, args.viewers)
    if args.viewers < 1 or args.keys < 2:
        parser.error("--viewers must be at least 1 and --keys at least 2")
    home = Path(tempfile.mkdtemp(prefix="racer-live-load-"))
    os.environ["RACER_TUI_HOME"] = str(home)
    os.environ.pop("RACER_TUI_LEAGUE", None)
    try:
        report = run(args.viewers, args.keys)
    except SoakError as error:
        print(f"benchmarks.web.live_load: {str(error).rstrip('.')}.", file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(home, ignore_errors=True)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    keys, behind = report["key_latency_ms"], report["viewers_behind_ms"]
    rss = report["server_rss_mb"]
    print(
        f"live page under load: {report['viewers']} viewers, {report['keys']} timekeeper keys, "
        f"{report['seconds']} s"
    )
    print(
        f"  timekeeper keys     p50 {keys['p50']:6.1f}  p95 {keys['p95']:6.1f}  "
        f"max {keys['max']:6.1f} ms   (target: p95 < {TARGET_KEY_P95_MS:g} ms)"
    )
    print(
        f"  viewers behind      p50 {behind['p50']:6.1f}  p95 {behind['p95']:6.1f}  "
        f"max {behind['max']:6.1f} ms   (target: < {TARGET_BEHIND_MS:g} ms)"
    )
    print(
        f"  server CPU          {report['server_core_share'] * 100:5.1f}% of a core"
        f"        (target: < {TARGET_SERVER_CORE * 100:g}%)"
    )
    print(
        f"  server memory       {rss['viewers_connected']:.1f} MB with the viewers "
        f"connected, {rss['end']:.1f} MB at the end (target: flat)"
    )
    print(
        f"  laps superseded     {report['laps_superseded']} (a heat's last lap, replaced by "
        "the next heat before a viewer's stream showed it)"
    )
    print(f"  events per viewer   p50 {report['events_per_viewer']['p50']:.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

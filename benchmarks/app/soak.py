"""Soak benchmark: the real app driven headless for thousands of key presses while a real
training runs beside it; prints memory growth, garbage-collection pauses and key latency.

`python -m benchmarks.app.soak [--actions 10000] [--no-training] [--json]`

The app is built as the launcher builds it (`create_app(long_running=True)`), in a fresh
temporary data home (`RACER_TUI_HOME`, set before this module imports anything of
racer_tui's or sim's) holding a model for the Garage, a second model that `racer-tui
train` trains in a child process for the whole run (`--no-training` skips it), three
recorded league races and a shared-folder store. Pilot then presses keys at 80x24 for N
actions, cycling through: section switches (1-5, most of the actions), the help screen and
the Garage's delete question (each opened and closed with Esc), the League's projector,
leaderboard sorting (s and r: the filters have no keys), a sync with the folder store
from the Sync screen, and every few hundred actions a heat: the reference driver's time
trial in Races, left when simulated, then its replay.

Figures, over the measured part (everything after the warm-up, the first 5% of the
actions and at least 50):
- this process's RSS and live objects (after `gc.collect()`, those the collector tracks
  plus those the app froze) after the warm-up, halfway and at the end, and their growth
  per 1,000 actions over the measured part and over its second half (a cache filling up
  flattens out in the second half; a leak does not);
- RSS at rest at the same points: right after giving free memory back to the system, as
  the long-running app does at every pause in input (`racer_tui.app.long_running`, at most every
  10 s). RSS taken at any other moment also counts what the C allocator holds free since
  the last pause, 0 to 15 MB here, which makes a growth figure over 10,000 actions mostly
  noise; the issue's growth target is judged on both, and both are printed;
- the longest garbage-collection pause and the number of full (generation 2) collections,
  from `gc.callbacks`;
- key latency p50 / p95 / max: from the moment Pilot sends the key to the first time the
  app hands the screen to its driver (`App._display`) with the key's effect visible (for a
  section switch: the new section's screen). Headless, `_display` returns before encoding
  and writing; the hook encodes each update to escape sequences as a terminal driver would
  (`render_segments`), so only the write itself is missing.
- a key in a terminal, at worst: Pilot sends its keys from the app's own event loop, so it
  never sends one while a collection holds the interpreter, and the latencies above never
  include a whole collection. A terminal's key arrives at any moment: one arriving as the
  longest collection starts waits for all of it, then is answered. Printed as the longest
  collection plus the median key latency, beside the same target.
Pauses and latencies are wall-clock times: on a machine with other work (the training
child takes most of a core) they include waiting for a CPU; the load average is printed.

Targets from the issue, printed beside the figures and never turned into the exit code:
growth under 1 MB per 1,000 actions after warm-up, key p95 under 50 ms, max under 100 ms.
The exit code is 0 whenever the benchmark ran; 1, with one sentence on stderr, when it
could not (the app or the training child failed to start, the app crashed).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import gc
import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import psutil

if TYPE_CHECKING:
    # Type names only: racer_tui's screens and sim are imported after RACER_TUI_HOME is set.
    from textual.pilot import Pilot
    from textual.screen import Screen

    from racer_tui.app.application import RacerTuiApp

DEFAULT_ACTIONS = 10_000
MIN_WARMUP = 50
WARMUP_FRACTION = 0.05
SIZE = (80, 24)
# A heat (a 4-minute time trial simulated in about a second, then its replay) and a sync
# are heavier than a key press; they come every few hundred and every hundred actions,
# the first ones early so that a short run exercises them too.
HEAT_EVERY, HEAT_FIRST = 250, 20
SYNC_EVERY, SYNC_FIRST = 100, 10
# The rest of the mix, repeated: section switches are the majority (and the actions that
# need a section insert a switch to it when they are elsewhere).
PATTERN = (
    "switch",
    "switch",
    "help",
    "switch",
    "sort",
    "switch",
    "switch",
    "projector",
    "switch",
    "delete-question",
    "switch",
    "switch",
    "sort",
    "switch",
    "switch",
)
NEEDS_SECTION = {
    "delete-question": "garage",
    "projector": "league",
    "sort": "league",
    "sync": "league",
    "heat": "races",
}
LONGEST_PAUSES_KEPT = 5  # the longest collections listed, each with who ran it
KEY_TIMEOUT = 10.0  # seconds to wait for a key's effect on screen before calling it unseen
WORK_TIMEOUT = 120.0  # a heat's simulation, a sync
RSS_SAMPLES = 10  # RSS (no collection, so no effect on the GC figures) along the measured part
TARGET_GROWTH_MB = 1.0
TARGET_P95_MS = 50.0
TARGET_MAX_MS = 100.0
TRAIN_MODEL = "soak-trainer"
GARAGE_MODEL = "soak"
RACERS = ("ada", "bob", "cy")


class SoakError(Exception):
    """The benchmark could not run; the message is one sentence for stderr."""


# --- figures -------------------------------------------------------------------------------


def percentiles(values: list[float]) -> dict[str, float | int]:
    """Count, p50, p95 and max by nearest rank (so p50 <= p95 <= max always holds)."""
    if not values:
        return {"count": 0, "p50": 0.0, "p95": 0.0, "max": 0.0}
    ordered = sorted(values)

    def rank(fraction: float) -> float:
        return round(ordered[max(0, math.ceil(len(ordered) * fraction) - 1)], 3)

    return {"count": len(ordered), "p50": rank(0.5), "p95": rank(0.95), "max": rank(1.0)}


def rss_mb() -> float:
    return float(psutil.Process().memory_info().rss) / 1e6


def rss_at_rest_mb() -> float:
    """RSS once free memory has gone back to the system, as the app does when input
    pauses (the raw RSS where the C library cannot: not glibc)."""
    from racer_tui.app.long_running import malloc_trim

    trim = malloc_trim()
    if trim is not None:
        trim()
    return rss_mb()


def live_objects() -> int:
    """Objects the collector tracks after a full collection, frozen ones included: the app
    freezes what survives its idle collections, and garbage frozen in a cycle stays until
    its next sweep, so leaving the frozen ones out would hide a leak."""
    gc.collect()
    return len(gc.get_objects()) + gc.get_freeze_count()


@dataclass
class GcWatch:
    """Pauses of every collection while `measuring` (gc.callbacks: start -> stop), and the
    longest few with who ran them (the app's collector: busy, idle, sweep; or Python) and
    how many objects each freed (a pause spent freeing a closed screen's garbage and one
    spent walking what lives call for different cures)."""

    measuring: bool = False
    collections: int = 0
    full_collections: int = 0
    longest_ms: float = 0.0
    total_ms: float = 0.0
    longest: list[tuple[float, int, str, int]] = field(default_factory=list)
    runner: Callable[[], str | None] = lambda: None
    _started: float = 0.0

    def __call__(self, phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            self._started = time.perf_counter()
            return
        if not self.measuring:
            return
        pause = (time.perf_counter() - self._started) * 1000.0
        self.collections += 1
        self.total_ms += pause
        self.longest_ms = max(self.longest_ms, pause)
        generation = int(info.get("generation", -1))
        if generation == 2:
            self.full_collections += 1
        freed = int(info.get("collected", 0))
        self.longest.append((pause, generation, self.runner() or "python", freed))
        self.longest.sort(reverse=True)
        del self.longest[LONGEST_PAUSES_KEPT:]


@dataclass
class Expectation:
    """A key sent at `sent_at`, waiting for a display where `visible(screen)` holds."""

    label: str
    visible: Callable[[Screen[Any]], bool]
    sent_at: float
    seen_at: float | None = None


class DisplayClock:
    """Wraps the app's `_display`, the one place each compositor update reaches the driver,
    and timestamps the first display at which the pending key's effect is visible."""

    def __init__(self, app: RacerTuiApp) -> None:
        from textual._compositor import CompositorUpdate

        self.pending: Expectation | None = None
        self.displays = 0
        original = app._display

        def display(screen: Screen[Any], renderable: Any) -> None:
            original(screen, renderable)
            if renderable is None or app._batch_count:
                return  # Textual draws nothing for these either
            if isinstance(renderable, CompositorUpdate):
                # What the terminal driver would do before writing (headless skips it).
                renderable.render_segments(app.console)
            now = time.perf_counter()
            self.displays += 1
            pending = self.pending
            if pending is not None and pending.seen_at is None and pending.visible(screen):
                pending.seen_at = now

        app._display = display  # type: ignore[method-assign]


# --- the data home -------------------------------------------------------------------------


def prepare_home(home: Path) -> str:
    """Models, league races and a shared-folder store in `home`; returns the store's URL."""
    from league.opening import open_league
    from league.races import record_race
    from league.sync.session import save_store
    from league.sync.stores import open_store
    from sim.garage.options import new_model
    from sim.race.engine import run_race
    from sim.tracks.catalog import DEFAULT_TRACK, resolve_track

    new_model(GARAGE_MODEL)
    new_model(TRAIN_MODEL, sensors=["vector"])  # a vector training is the light one
    # Leaderboard rows to sort and project: real reference-driver races, with traces.
    track = resolve_track(DEFAULT_TRACK)
    with open_league() as league:
        for seed, racer in enumerate(RACERS, start=1):
            record_race(league, run_race(track, racer=racer, seed=seed))
    url = f"dir:{home / 'league-share'}"
    with open_store(url) as store:
        store.init()
    with open_league() as league:
        save_store(league, url)
    return url


# --- the training child --------------------------------------------------------------------


@dataclass
class TrainingChild:
    process: subprocess.Popen[bytes]
    events_file: Path
    errors_file: Path
    started: float


def start_training(home: Path, minutes: float) -> TrainingChild:
    """`racer-tui train MODEL --json`, as a racer would run it beside the app."""
    events_file, errors_file = home / "train-events.jsonl", home / "train-stderr.txt"
    command = [
        sys.executable,
        "-m",
        "racer_tui.cli.main",
        "train",
        TRAIN_MODEL,
        "--minutes",
        f"{minutes:g}",
        "--json",
    ]
    with events_file.open("wb") as out, errors_file.open("wb") as err:
        # Its own session: a Ctrl+C meant for the benchmark does not stop it halfway.
        process = subprocess.Popen(
            command,
            stdout=out,
            stderr=err,
            env={**os.environ},
            start_new_session=True,
        )
    child = TrainingChild(process, events_file, errors_file, time.perf_counter())
    deadline = time.monotonic() + 180.0
    while time.monotonic() < deadline:
        if any(event.get("type") == "started" for event in read_events(events_file)):
            return child
        if process.poll() is not None:
            raise SoakError(
                f"the training child exited with code {process.returncode} before it "
                f"started: {last_line(errors_file) or 'no message'}"
            )
        time.sleep(0.2)
    stop_process(process)
    raise SoakError("the training child did not report its start within 180 s")


def read_events(path: Path) -> list[dict[str, Any]]:
    events: list[dict[str, Any]] = []
    for line in path.read_text(errors="replace").splitlines():
        try:
            event = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line still being written
        if isinstance(event, dict):
            events.append(event)
    return events


def last_line(path: Path) -> str:
    lines = [line for line in path.read_text(errors="replace").splitlines() if line.strip()]
    return lines[-1].strip() if lines else ""


def stop_process(process: subprocess.Popen[bytes]) -> str:
    """SIGINT (the CLI asks its worker to checkpoint and stop), then kill after 30 s."""
    if process.poll() is not None:
        return "had exited"
    try:
        children = psutil.Process(process.pid).children(recursive=True)
    except psutil.Error:
        children = []
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=30)
        return "stopped with SIGINT"
    except subprocess.TimeoutExpired:
        for child in children:  # the worker is in a session of its own
            with contextlib.suppress(psutil.Error):
                child.kill()
        process.kill()
        process.wait()
        return "killed: it did not stop within 30 s of SIGINT"


def finish_training(child: TrainingChild) -> dict[str, Any]:
    running = child.process.poll() is None
    ran_for = time.perf_counter() - child.started
    how = stop_process(child.process)
    events = read_events(child.events_file)
    kinds = Counter(str(event.get("type")) for event in events)
    ended = next(
        (e for e in reversed(events) if e.get("type") in ("stopped", "finished", "failed")),
        None,
    )
    steps = max((int(e.get("total_steps", 0) or 0) for e in events), default=0)
    return {
        "ran": True,
        "running_at_end": running,
        "ran_for_s": round(ran_for, 1),
        "stop": how,
        "exit_code": child.process.returncode,
        "events": dict(sorted(kinds.items())),
        "total_steps": steps,
        "ended": None if ended is None else f"{ended.get('type')}: {ended.get('message', '')}",
        "stderr": last_line(child.errors_file),
    }


# --- the soak ------------------------------------------------------------------------------


def plan() -> Iterator[str]:
    """The action kinds in order, forever."""
    k = 0
    while True:
        if k % HEAT_EVERY == HEAT_FIRST:
            yield "heat"
        elif k % SYNC_EVERY == SYNC_FIRST:
            yield "sync"
        else:
            yield PATTERN[k % len(PATTERN)]
        k += 1


@dataclass
class Soak:
    app: RacerTuiApp
    pilot: Pilot[int]
    clock: DisplayClock
    gc_watch: GcWatch
    rng: random.Random = field(default_factory=lambda: random.Random(7))
    measuring: bool = False
    latencies: dict[str, list[float]] = field(default_factory=dict)
    warmup_latencies: list[float] = field(default_factory=list)
    unseen: Counter[str] = field(default_factory=Counter)
    recoveries: Counter[str] = field(default_factory=Counter)
    counts: Counter[str] = field(default_factory=Counter)
    heat_seconds: list[float] = field(default_factory=list)
    sync_seconds: list[float] = field(default_factory=list)
    notices: Counter[str] = field(default_factory=Counter)

    # --- keys and waits --------------------------------------------------------------------

    async def key(self, key: str, label: str, visible: Callable[[Screen[Any]], bool]) -> None:
        """Press `key`; its latency is sent -> first display where `visible` holds. Pilot's
        own wait (until the app is idle) is not the latency: the hook's timestamp is."""
        app = self.app

        def shown(screen: Screen[Any]) -> bool:
            return screen is app.screen and visible(screen)

        expectation = Expectation(label, shown, time.perf_counter())
        self.clock.pending = expectation
        await self.pilot.press(key)
        deadline = time.perf_counter() + KEY_TIMEOUT
        # Plain sleeps, not pilot.pause(): that forces a screen refresh the app would not do.
        while expectation.seen_at is None and time.perf_counter() < deadline:
            await asyncio.sleep(0.002)
        self.clock.pending = None
        if expectation.seen_at is None:
            self.unseen[label] += 1
            return
        ms = (expectation.seen_at - expectation.sent_at) * 1000.0
        if self.measuring:
            self.latencies.setdefault(label, []).append(ms)
        else:
            self.warmup_latencies.append(ms)

    async def until(self, condition: Callable[[], bool], timeout: float = WORK_TIMEOUT) -> bool:
        deadline = time.perf_counter() + timeout
        while not condition():
            if time.perf_counter() > deadline:
                return False
            await asyncio.sleep(0.02)
        return True

    def on_section(self) -> bool:
        from racer_tui.app.sections import section_for

        app = self.app
        return len(app.screen_stack) == 1 and section_for(app.current_mode) is not None

    def back_on_section(self, screen: Screen[Any]) -> bool:
        return self.on_section() and screen is self.app.section_base

    async def recover(self, after: str) -> None:
        """Escape back to a section screen if an action left something open."""
        for _ in range(5):
            if self.on_section():
                return
            self.recoveries[after] += 1
            await self.pilot.press("escape")
            await self.until(self.on_section, 2.0)
        if not self.on_section():
            raise SoakError(
                f"after a {after} action the app stayed on {type(self.app.screen).__name__} "
                "and five presses of Esc did not bring it back to a section"
            )

    # --- actions ---------------------------------------------------------------------------

    async def switch(self, mode: str | None = None) -> None:
        from racer_tui.app.application import SECTION_SCREENS
        from racer_tui.app.sections import SECTIONS

        if mode is None:
            mode = self.rng.choice([s.mode for s in SECTIONS if s.mode != self.app.current_mode])
        section = next(s for s in SECTIONS if s.mode == mode)
        target = SECTION_SCREENS[mode]
        await self.key(
            section.key,
            "section switch",
            lambda screen: isinstance(screen, target) and self.on_section(),
        )

    async def dialog(self, key: str, label: str, screen_class: type[Screen[Any]]) -> None:
        await self.key(key, f"{label}: open", lambda screen: isinstance(screen, screen_class))
        await self.key("escape", f"{label}: close", self.back_on_section)

    async def help(self) -> None:
        from racer_tui.app.screens.help import HelpScreen

        await self.dialog("question_mark", "help", HelpScreen)

    async def delete_question(self) -> None:
        from racer_tui.app.screens.dialogs import ConfirmDialog
        from racer_tui.app.screens.garage import GarageScreen

        garage = self.app.section_base
        assert isinstance(garage, GarageScreen)
        await self.until(lambda: garage.highlighted_name is not None, KEY_TIMEOUT)
        # Esc answers no: the model stays (y would delete it, and is never pressed here).
        await self.dialog("d", "delete question", ConfirmDialog)

    async def projector(self) -> None:
        from racer_tui.app.screens.kiosk import LeaveKiosk
        from racer_tui.app.screens.projector import ProjectorScreen

        # A kiosk: Esc does nothing there; q asks, y leaves.
        await self.key("p", "projector: open", lambda screen: isinstance(screen, ProjectorScreen))
        await self.key("q", "projector: ask", lambda screen: isinstance(screen, LeaveKiosk))
        await self.key("y", "projector: close", self.back_on_section)

    async def sort(self) -> None:
        from racer_tui.app.screens.league import LeagueScreen

        base = self.app.section_base
        assert isinstance(base, LeagueScreen)
        league: LeagueScreen = base  # typed for the closures below
        await self.until(lambda: league.loaded, KEY_TIMEOUT)
        before = league.order
        # Mostly the next column (s), every third time the other direction (r).
        key, label = ("r", "sort reverse") if self.counts["sort"] % 3 == 2 else ("s", "sort")
        await self.key(key, label, lambda screen: screen is league and league.order != before)

    async def sync(self) -> None:
        from racer_tui.app.screens.sync import SyncScreen

        await self.key("y", "sync: open", lambda screen: isinstance(screen, SyncScreen))
        opened = self.app.screen
        if not isinstance(opened, SyncScreen):
            return
        screen: SyncScreen = opened  # typed for the closures below
        # The store's URL is filled in from the status read; s before it would ask for one.
        await self.until(lambda: screen.status is not None, KEY_TIMEOUT)
        before = screen.last_summary
        started = time.perf_counter()
        await self.key(
            "s",
            "sync: run",
            lambda shown: shown is screen and (screen.syncing or screen.last_summary is not before),
        )
        await self.until(lambda: not screen.syncing and screen.last_summary is not before)
        self.sync_seconds.append(time.perf_counter() - started)
        await self.key("escape", "sync: close", self.back_on_section)

    async def heat(self) -> None:
        from racer_tui.app.screens.race_screen import RaceScreen
        from racer_tui.app.screens.races import RacesScreen

        races = self.app.section_base
        assert isinstance(races, RacesScreen)
        await self.until(lambda: races.chosen_driver is not None, KEY_TIMEOUT)
        started = time.perf_counter()
        await self.key("s", "heat: start", lambda screen: isinstance(screen, RaceScreen))
        race = self.app.screen
        if isinstance(race, RaceScreen):
            await self.until(lambda: race.result is not None or race.failure is not None)
            self.heat_seconds.append(time.perf_counter() - started)
            await self.key("escape", "heat: leave", self.back_on_section)
        await self.recover("heat")
        # The replay of the race just run (this session's highlighted result).
        await self.key(
            "p",
            "heat: replay",
            lambda screen: (
                isinstance(screen, RaceScreen)
                and screen is not race
                and screen.setup.replay is not None
            ),
        )
        replay = self.app.screen
        if isinstance(replay, RaceScreen):
            await self.until(lambda: replay.frames >= 15, KEY_TIMEOUT)  # half a second drawn
            await self.key("escape", "heat: leave replay", self.back_on_section)

    async def run_action(self, kind: str, mode: str | None = None) -> None:
        """One action of `kind` (a switch to `mode`, if given), then back to a section."""
        actions: dict[str, Callable[[], Any]] = {
            "switch": lambda: self.switch(mode),
            "help": self.help,
            "delete-question": self.delete_question,
            "projector": self.projector,
            "sort": self.sort,
            "sync": self.sync,
            "heat": self.heat,
        }
        await actions[kind]()
        self.counts[kind] += 1
        await self.recover(kind)


@dataclass
class Snapshot:
    actions: int
    rss_mb: float
    objects: int  # after a full collection
    rest_mb: float  # RSS after that collection and a trim

    @classmethod
    def now(cls, actions: int) -> Snapshot:
        rss = rss_mb()  # first: the collection and the trim below change it
        objects = live_objects()
        return cls(actions, rss, objects, rss_at_rest_mb())


def growth(
    points: tuple[Snapshot, Snapshot, Snapshot], figure: str, digits: int | None, per: int
) -> dict[str, Any]:
    """A figure after warm-up, halfway and at the end (rounded to `digits`), and its growth
    per 1,000 actions over the measured part and over its second half (to `per` digits)."""
    warm, middle, end = (getattr(point, figure) for point in points)
    per_k = 1000.0 / max(1, points[2].actions - points[0].actions)
    per_k_half = 1000.0 / max(1, points[2].actions - points[1].actions)
    return {
        "after_warmup": round(warm, digits),
        "end": round(end, digits),
        "growth_per_1000_actions": round((end - warm) * per_k, per),
        "halfway": round(middle, digits),
        "second_half_growth_per_1000_actions": round((end - middle) * per_k_half, per),
    }


async def soak(actions: int, warmup: int, started: float) -> dict[str, Any]:
    """Drive the app for `actions` actions; the figures of the part after `warmup`."""
    from racer_tui.app.application import create_app

    app = create_app(long_running=True)
    gc_watch = GcWatch(runner=lambda: app.collector.running)
    gc.callbacks.append(gc_watch)
    samples: list[tuple[int, float]] = []
    try:
        async with app.run_test(size=SIZE) as pilot:
            clock = DisplayClock(app)
            runner = Soak(app, pilot, clock, gc_watch)
            original_notify = app.notify

            def notify(message: str, **options: Any) -> None:
                severity = str(options.get("severity", "information"))
                if severity in ("warning", "error"):
                    runner.notices[f"{severity}: {message}"] += 1
                original_notify(message, **options)

            app.notify = notify  # type: ignore[method-assign]
            if not await runner.until(runner.on_section, 60.0):
                raise SoakError("the app did not open a section within 60 s of starting")
            # The long-running app freezes its start-up objects after its first refresh.
            await runner.until(lambda: gc.get_freeze_count() > 0, 10.0)
            warm: Snapshot | None = None
            middle: Snapshot | None = None
            halfway = warmup + (actions - warmup) // 2
            measured_started = time.perf_counter()
            sample_every = max(1, (actions - warmup) // RSS_SAMPLES)
            done = 0
            kinds = plan()
            kind = next(kinds)
            while done < actions:
                need = NEEDS_SECTION.get(kind)
                if need is not None and app.current_mode != need:
                    await runner.run_action("switch", need)
                else:
                    await runner.run_action(kind)
                    kind = next(kinds)
                done += 1
                if done == warmup:
                    warm = Snapshot.now(done)
                    runner.measuring = gc_watch.measuring = True
                    measured_started = time.perf_counter()
                elif done == halfway:
                    # A bounded cache fills up and stops; a leak keeps going: the second
                    # half's growth tells them apart. Its own full collection is not counted.
                    gc_watch.measuring = False
                    middle = Snapshot.now(done)
                    gc_watch.measuring = True
                if done > warmup and (done - warmup) % sample_every == 0:
                    samples.append((done, round(rss_mb(), 1)))
            gc_watch.measuring = False
            measured_s = time.perf_counter() - measured_started
            end = Snapshot.now(done)
            on_section = runner.on_section()
            mode = app.current_mode
    finally:
        gc.callbacks.remove(gc_watch)
    assert warm is not None
    middle = middle or warm  # fewer than two measured actions: no halves
    points = (warm, middle, end)
    all_keys = [ms for values in runner.latencies.values() for ms in values]
    notes = []
    if runner.unseen:
        notes.append(
            "keys whose effect never reached the screen within "
            f"{KEY_TIMEOUT:g} s (left out of the latencies): "
            + ", ".join(f"{label} x{n}" for label, n in sorted(runner.unseen.items()))
        )
    if runner.recoveries:
        notes.append(
            "actions that left a screen open, closed with extra Esc presses: "
            + ", ".join(f"{label} x{n}" for label, n in sorted(runner.recoveries.items()))
        )
    for text, n in sorted(runner.notices.items()):
        notes.append(f"the app notified x{n}: {text}")
    return {
        "actions": done,
        "warmup_actions": warmup,
        "measured_actions": end.actions - warm.actions,
        "measured_seconds": round(measured_s, 1),
        "displays": clock.displays,
        "rss_mb": {**growth(points, "rss_mb", 1, 3), "samples": samples},
        "rss_at_rest_mb": growth(points, "rest_mb", 1, 3),
        "objects": {
            **growth(points, "objects", None, 1),
            "frozen_at_end": gc.get_freeze_count(),
        },
        "gc": {
            "longest_pause_ms": round(gc_watch.longest_ms, 3),
            "longest_pauses": [
                {"ms": round(ms, 1), "generation": generation, "run_by": by, "freed": freed}
                for ms, generation, by, freed in gc_watch.longest
            ],
            "full_collections": gc_watch.full_collections,
            "collections": gc_watch.collections,
            "total_pause_ms": round(gc_watch.total_ms, 1),
            "idle_collections": app.collector.collections - app.collector.busy_collections,
            "busy_collections": app.collector.busy_collections,
            "sweeps": app.collector.sweeps,
            "memory_returned_to_the_system": app.collector.trims,
        },
        "key_latency_ms": percentiles(all_keys),
        "terminal_key_worst_ms": round(
            gc_watch.longest_ms + float(percentiles(all_keys)["p50"]), 1
        ),
        "section_switch_latency_ms": percentiles(runner.latencies.get("section switch", [])),
        "latency_by_key_ms": {
            label: percentiles(values) for label, values in sorted(runner.latencies.items())
        },
        "warmup_key_latency_ms": percentiles(runner.warmup_latencies),
        "action_counts": dict(sorted(runner.counts.items())),
        "heat_simulation_s": percentiles(runner.heat_seconds),
        "sync_s": percentiles(runner.sync_seconds),
        "ended_on_section": on_section,
        "ended_in": mode,
        "wall_seconds": round(time.perf_counter() - started, 1),
        "notes": notes,
    }


# --- output --------------------------------------------------------------------------------


def print_report(report: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    rss, objects, gc_figures = report["rss_mb"], report["objects"], report["gc"]
    keys, switches = report["key_latency_ms"], report["section_switch_latency_ms"]
    table = Table(
        title=(
            f"soak: {report['actions']:,} actions ({report['warmup_actions']} warm-up), "
            f"{report['wall_seconds']:g} s"
        ),
        title_justify="left",
    )
    table.add_column("figure")
    table.add_column("value", justify="right")
    table.add_column("target", style="dim")
    table.add_row(
        "RSS MB after warm-up / halfway / end",
        f"{rss['after_warmup']:.1f} / {rss['halfway']:.1f} / {rss['end']:.1f}",
        "",
    )
    table.add_row(
        "RSS growth per 1,000 actions",
        f"{rss['growth_per_1000_actions']:+.3f} MB",
        f"< {TARGET_GROWTH_MB:g} MB",
    )
    table.add_row(
        "  in the second half",
        f"{rss['second_half_growth_per_1000_actions']:+.3f} MB",
        f"< {TARGET_GROWTH_MB:g} MB",
    )
    rest = report["rss_at_rest_mb"]
    table.add_row(
        "RSS at rest after warm-up / halfway / end",
        f"{rest['after_warmup']:.1f} / {rest['halfway']:.1f} / {rest['end']:.1f}",
        "",
    )
    table.add_row(
        "RSS at rest growth per 1,000 actions",
        f"{rest['growth_per_1000_actions']:+.3f} MB",
        f"< {TARGET_GROWTH_MB:g} MB",
    )
    table.add_row(
        "  in the second half",
        f"{rest['second_half_growth_per_1000_actions']:+.3f} MB",
        f"< {TARGET_GROWTH_MB:g} MB",
    )
    table.add_row(
        "objects after warm-up / halfway / end",
        f"{objects['after_warmup']:,} / {objects['halfway']:,} / {objects['end']:,}",
        "",
    )
    table.add_row(
        "objects growth per 1,000 actions", f"{objects['growth_per_1000_actions']:+,.1f}", ""
    )
    table.add_row(
        "  in the second half", f"{objects['second_half_growth_per_1000_actions']:+,.1f}", ""
    )
    table.add_row("of them frozen at the end", f"{objects['frozen_at_end']:,}", "")
    table.add_row("longest GC pause", f"{gc_figures['longest_pause_ms']:.1f} ms", "")
    table.add_row(
        "  the longest, ms (generation, run by, objects freed)",
        ", ".join(
            f"{pause['ms']:.0f} ({pause['generation']}, {pause['run_by']}, {pause['freed']:,})"
            for pause in gc_figures["longest_pauses"]
        ),
        "",
    )
    table.add_row(
        "full (gen 2) / all collections",
        f"{gc_figures['full_collections']} / {gc_figures['collections']}",
        "",
    )
    table.add_row(
        "of the full ones, run at idle / while keys kept coming / sweeps",
        f"{gc_figures['idle_collections']} / {gc_figures['busy_collections']} / "
        f"{gc_figures['sweeps']}",
        "",
    )
    table.add_row(
        "free memory returned to the system",
        f"{gc_figures['memory_returned_to_the_system']} times",
        "",
    )
    for name, figures in (("key", keys), ("section switch", switches)):
        table.add_row(
            f"{name} latency p50 / p95 / max ({figures['count']})",
            f"{figures['p50']:.1f} / {figures['p95']:.1f} / {figures['max']:.1f} ms",
            f"p95 < {TARGET_P95_MS:g}, max < {TARGET_MAX_MS:g}",
        )
    table.add_row(
        "a key in a terminal, at worst (longest collection + key p50)",
        f"{report['terminal_key_worst_ms']:.1f} ms",
        f"max < {TARGET_MAX_MS:g}",
    )
    console.print(table)
    by_key = Table(title="latency by key, ms (after warm-up)", title_justify="left")
    for column in ("key", "n", "p50", "p95", "max"):
        by_key.add_column(column, justify="left" if column == "key" else "right")
    for label, figures in report["latency_by_key_ms"].items():
        by_key.add_row(
            label,
            str(figures["count"]),
            f"{figures['p50']:.1f}",
            f"{figures['p95']:.1f}",
            f"{figures['max']:.1f}",
        )
    console.print(by_key)
    counts = ", ".join(f"{kind} {n:,}" for kind, n in report["action_counts"].items())
    console.print(f"actions: {counts}", markup=False)
    heat, sync = report["heat_simulation_s"], report["sync_s"]
    if heat["count"]:
        console.print(f"heat start to result: median {heat['p50']:.2f} s, max {heat['max']:.2f} s")
    if sync["count"]:
        console.print(f"sync run: median {sync['p50']:.2f} s, max {sync['max']:.2f} s")
    warm = report["warmup_key_latency_ms"]
    console.print(
        f"warm-up keys ({warm['count']}): p50 {warm['p50']:.1f} / p95 {warm['p95']:.1f} / "
        f"max {warm['max']:.1f} ms (first visits; not in the figures above)"
    )
    console.print(f"RSS along the measured part: {report['rss_mb']['samples']}", markup=False)
    training = report["training"]
    if training["ran"]:
        console.print(
            f"training child: running at the end {training['running_at_end']}, ran "
            f"{training['ran_for_s']:g} s, {training['total_steps']:,} steps, "
            f"{training['stop']}, ended {training['ended']}",
            markup=False,
        )
    console.print(f"ended on a section screen: {report['ended_on_section']} ({report['ended_in']})")
    machine = report["machine"]
    console.print(
        f"machine: {machine['cpus']} CPUs, load average {machine['load_average_start']} at "
        f"the start, {machine['load_average_end']} at the end (other processes count too)"
    )
    for note in report["notes"]:
        console.print(f"note: {note}", markup=False, soft_wrap=True)


# --- main ----------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--actions", type=int, default=DEFAULT_ACTIONS)
    parser.add_argument("--no-training", action="store_true", help="no training child")
    parser.add_argument(
        "--training-minutes",
        type=float,
        help="the child's time limit (default: 10 + one per 100 actions, to outlast the run)",
    )
    parser.add_argument("--keep-home", action="store_true", help="keep the temporary data home")
    parser.add_argument("--json", action="store_true", help="one JSON object")
    args = parser.parse_args(argv)
    if args.actions <= MIN_WARMUP:
        parser.error(f"--actions must be more than the {MIN_WARMUP} warm-up actions")
    warmup = max(MIN_WARMUP, int(args.actions * WARMUP_FRACTION))
    started = time.perf_counter()
    load_at_start = round(os.getloadavg()[0], 2)
    # Before anything of racer_tui's or sim's that reads it is imported (they read it lazily,
    # but the rule keeps this benchmark from ever touching a real garage).
    home = Path(tempfile.mkdtemp(prefix="racer-soak-"))
    os.environ["RACER_TUI_HOME"] = str(home)
    os.environ.pop("RACER_TUI_LEAGUE", None)  # the league of the temporary home
    child: TrainingChild | None = None
    training: dict[str, Any] = {"ran": False}
    try:
        prepare_home(home)
        if not args.no_training:
            minutes = args.training_minutes or 10.0 + args.actions / 100.0
            child = start_training(home, minutes)
        report = asyncio.run(soak(args.actions, warmup, started))
    except SoakError as error:
        print(f"benchmarks.app.soak: {str(error).rstrip('.')}.", file=sys.stderr)
        return 1
    except Exception as error:
        print(
            f"benchmarks.app.soak: the benchmark could not run: {type(error).__name__}: {error}",
            file=sys.stderr,
        )
        return 1
    finally:
        if child is not None:
            training = finish_training(child)
        if not args.keep_home:
            shutil.rmtree(home, ignore_errors=True)
    report["training"] = training
    report["machine"] = {
        "cpus": os.cpu_count(),
        "load_average_start": load_at_start,
        "load_average_end": round(os.getloadavg()[0], 2),
    }
    report["home"] = str(home) if args.keep_home else None
    if args.no_training:
        report["notes"].append("no training child (--no-training)")
    elif not training.get("running_at_end"):
        report["notes"].append("the training child was not running at the end of the soak")
    report["notes"].append(
        "leaderboard filters have no keys (they are Select widgets): the sort keys s and r "
        "are the leaderboard actions"
    )
    report["notes"].append(
        "each heat's result (with its trace) stays in the app's session list, as the app "
        "keeps every race of a session: the growth includes them"
    )
    report["targets"] = {
        "growth_mb_per_1000_actions_under": TARGET_GROWTH_MB,
        "key_p95_ms_under": TARGET_P95_MS,
        "key_max_ms_under": TARGET_MAX_MS,
    }
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print_report(report)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

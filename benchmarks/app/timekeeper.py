"""How fast the timekeeper answers its keys while the machine is busy.

    python -m benchmarks.app.timekeeper [--keys 300] [--no-training] [--json]

Drives the real app headless through Pilot, with the timekeeper open on a physical car's
heat (each input also written to the heat's journal, as on a night), in three conditions
one after the other: nothing else running; simulated races back to back in a thread of
the app's own process (as an evaluation or a race view computes them: the harshest case,
since they share one interpreter with the keys); a vector training child at full load
(`racer-tui train`, as a host runs one beside the app). In each, `--keys` presses
alternate Car Reset (`r`) and Capture Lap (`l`), in heats of 24 laps (a 4-minute heat of
10 s laps, then the next); a key's
latency is from the press to the first screen update that shows its effect (the sentence
the timekeeper says), timed where Textual hands each update to the terminal
(`benchmarks.app.soak.DisplayClock`). Figures are printed, never judged here; the target
(issue 15) is p95 under 50 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rich.text import Text
from textual.screen import Screen

from benchmarks.app.soak import (
    GARAGE_MODEL,
    TRAIN_MODEL,
    DisplayClock,
    Expectation,
    SoakError,
    TrainingChild,
    finish_training,
    percentiles,
    start_training,
)

SIZE = (80, 24)
KEY_TIMEOUT = 5.0
LAP_SECONDS = 10.0  # the timekeeper's own clock moves this much per captured lap
HEAT_KEYS = 48  # 24 laps of 10 s: a 4-minute heat


class BusyHeat:
    """A simulated heat after another, in a thread of this process, until stopped."""

    def __init__(self) -> None:
        self._stop = threading.Event()
        self.heats = 0
        self._thread = threading.Thread(target=self._race, daemon=True)

    def _race(self) -> None:
        from sim.race.engine import run_race
        from sim.tracks.catalog import DEFAULT_TRACK, resolve_track

        track = resolve_track(DEFAULT_TRACK)
        while not self._stop.is_set():
            run_race(track, racer="busy", seed=self.heats)
            self.heats += 1

    def __enter__(self) -> BusyHeat:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join(timeout=60)


async def press_keys(
    keys: int,
    *,
    night_id: str | None = None,
    lap_captured: Callable[[int, float], None] | None = None,
) -> list[float]:
    """Time `keys` alternating r and l presses, in heats of `HEAT_KEYS` (a new timekeeper
    for each, started with space, as a night's physical heats follow one another).

    With `night_id`, each heat is also written for the night's projector and web pages
    (`league.live_heat`), as a night's heat is; `lap_captured(laps, at)` hears each
    captured lap: the heat's laps so far and the wall-clock time of the key."""
    from league.live_heat import LiveHeatWriter, live_heat_path
    from league.store import default_db_path
    from league.timekeeper.journal import HeatJournal, journal_path
    from racer_tui.app.application import create_app
    from racer_tui.app.screens.timekeeper import TimekeeperScreen, TimekeeperSetup
    from sim.foundation.ids import new_id
    from sim.race.rules import RaceRules
    from sim.tracks.catalog import DEFAULT_TRACK, resolve_track

    app = create_app(long_running=True)
    latencies: list[float] = []
    rules = RaceRules(window_seconds=3600.0, max_offtracks_per_lap=None)
    track = resolve_track(DEFAULT_TRACK)
    moment = [0.0]
    async with app.run_test(size=SIZE) as pilot:
        clock = DisplayClock(app)
        keeper: TimekeeperScreen | None = None
        for press in range(keys):
            if press % HEAT_KEYS == 0:
                if keeper is not None:
                    app.pop_screen()
                # As on a night: every input also goes to the heat's journal on disk.
                heat_id = new_id()
                journal = HeatJournal(journal_path(default_db_path(), heat_id), heat_id)
                live = None
                if night_id is not None:
                    live = LiveHeatWriter(
                        live_heat_path(default_db_path(), night_id),
                        night_id=night_id,
                        heat_id=heat_id,
                        heat_number=press // HEAT_KEYS + 1,
                        racer="bench",
                        car="bench car",
                    )
                setup = TimekeeperSetup(
                    track, rules, "bench", "bench car", journal=journal, live=live
                )
                keeper = TimekeeperScreen(setup)
                keeper.clock = lambda: moment[0]
                await app.push_screen(keeper)
                await pilot.press("space")
            assert keeper is not None
            key = "r" if press % 2 == 0 else "l"
            if key == "l":
                moment[0] += LAP_SECONDS
            said = "this lap." if key == "r" else "counts."

            def answered(
                screen: Screen[Any], said: str = said, keeper: TimekeeperScreen = keeper
            ) -> bool:
                return screen is keeper and str(keeper.said).endswith(said)

            expectation = Expectation(key, answered, time.perf_counter())
            keeper.said = Text("")  # the next sentence is this key's
            clock.pending = expectation
            if key == "l" and lap_captured is not None:
                lap_captured(press % HEAT_KEYS // 2 + 1, time.time())
            await pilot.press(key)
            deadline = time.perf_counter() + KEY_TIMEOUT
            while expectation.seen_at is None and time.perf_counter() < deadline:
                await asyncio.sleep(0.002)
            clock.pending = None
            if expectation.seen_at is None:
                raise SoakError(f"key {key!r} (press {press + 1}) was not seen within 5 s")
            latencies.append((expectation.seen_at - expectation.sent_at) * 1000.0)
    return latencies


def run(keys: int, home: Path, *, training: bool = True) -> dict[str, Any]:
    from sim.garage.options import new_model

    new_model(GARAGE_MODEL)
    new_model(TRAIN_MODEL, sensors=["vector"])
    conditions: dict[str, Any] = {}
    conditions["idle"] = percentiles(asyncio.run(press_keys(keys)))
    with BusyHeat() as busy:
        conditions["simulated heat in the app"] = percentiles(asyncio.run(press_keys(keys)))
    report: dict[str, Any] = {"keys_per_condition": keys, "latency_ms": conditions}
    report["heats_raced_beside"] = busy.heats
    if training:
        child: TrainingChild = start_training(home, 30.0)
        try:
            conditions["training at full load"] = percentiles(asyncio.run(press_keys(keys)))
        finally:
            ended = finish_training(child)
        report["training"] = {key: ended[key] for key in ("stop", "total_steps", "ended")}
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--keys", type=int, default=300)
    parser.add_argument("--no-training", action="store_true", help="skip the training condition")
    parser.add_argument("--json", action="store_true", help="one JSON object")
    args = parser.parse_args(argv)
    if args.keys < 2:
        parser.error("--keys must be at least 2")
    home = Path(tempfile.mkdtemp(prefix="racer-timekeeper-"))
    os.environ["RACER_TUI_HOME"] = str(home)
    os.environ.pop("RACER_TUI_LEAGUE", None)
    try:
        report = run(args.keys, home, training=not args.no_training)
    except SoakError as error:
        print(f"benchmarks.app.timekeeper: {str(error).rstrip('.')}.", file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(home, ignore_errors=True)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"timekeeper key latency, {args.keys} keys per condition (target: p95 < 50 ms)")
    for name, figures in report["latency_ms"].items():
        print(
            f"  {name:<28} p50 {figures['p50']:6.1f}  p95 {figures['p95']:6.1f}  "
            f"max {figures['max']:6.1f} ms"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

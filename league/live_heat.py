"""The heat running now, for the venue's projector and the web: a small JSON file beside the
league.

A heat runs in the host's racer-tui (the race view, or the timekeeper for a physical
car); the night's projector is often another racer-tui, in another terminal on the
venue's screen, and `racer-tui serve` shows it on the web (`/live`). Results reach them
through the league database, but the heat in progress is not in the database until it
ends. So the screen running it writes where it is (clock, lap, laps, best lap, and a
simulated car's place) to `live-heats/<night id>.json` beside the league file,
atomically, and the others read it.

The writer writes at once when the state, the lap, the laps, the off-tracks or the best
lap change, every `MOVING_SECONDS` while a simulated car moves (for the web page's map),
and at least every `HEARTBEAT_SECONDS` even while a heat stands still; a file older than
`STALE_SECONDS` belongs to a racer-tui that was closed or killed mid-heat, and the readers
then show no heat running. The file is untrusted input like any other: a reader that finds
anything unexpected in it treats it as absent.
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, TypeVar

from sim.foundation.atomic import write_text_atomic
from sim.race.result import LapRecord

FOLDER = "live-heats"
HEARTBEAT_SECONDS = 0.5
# A web viewer's map is to follow the race view within a quarter of a second: the car's
# place is written this often while it moves.
MOVING_SECONDS = 0.1
STALE_SECONDS = 5.0
MAX_TEXT = 200
MAX_LAPS = 200  # a 4-minute heat drives 20-40 laps; a lap-count race at most its count
MAX_BYTES = 32_768
STATES = ("ready", "running", "paused", "over")
Parsed = TypeVar("Parsed")


@dataclass(frozen=True)
class LiveLap:
    """A lap the heat has completed, as the race view's lap table shows it."""

    time_seconds: float  # penalties included
    penalty_seconds: float
    offtracks: int
    counts: bool  # within the rules' off-track limit (and not struck out)


@dataclass(frozen=True)
class LiveHeat:
    """Where the heat in progress is, as the screen running it shows it."""

    night_id: str
    heat_id: str
    heat_number: int  # in the night's running order, from 1
    racer: str  # the racer's display name
    car: str  # the model, bundle or physical car
    state: str  # one of STATES
    time_left: float  # seconds of the race window
    lap: int  # the lap in progress, from 1
    lap_time: float  # seconds into it
    best_lap: float | None  # the best lap that counts so far
    offtracks: int  # this lap's off-tracks (a physical car's resets)
    limit: int | None  # the rules' off-track limit per lap
    written_at: float = 0.0  # wall clock (time.time()) of the write
    laps: tuple[LiveLap, ...] = ()  # completed laps (absent from files of earlier writers)
    car_at: tuple[float, float] | None = None  # a simulated car's place, metres


def live_laps(laps: Sequence[LapRecord]) -> tuple[LiveLap, ...]:
    """A heat's completed laps as the file holds them."""
    return tuple(
        LiveLap(lap.time_seconds, lap.penalty_seconds, lap.offtracks, lap.valid) for lap in laps
    )


def live_heat_path(league_file: Path, night_id: str) -> Path:
    return league_file.parent / FOLDER / f"{night_id}.json"


def read_live_heat(path: Path, night_id: str, now: float | None = None) -> LiveHeat | None:
    """The heat running now on night `night_id`, or None: no file, a stale one, or one
    that does not hold what a writer writes."""
    heat = read_live_file(path, _parse)
    if heat is None or heat.night_id != night_id or not is_fresh(heat.written_at, now):
        return None
    return heat


def read_live_file(path: Path, parse: Callable[[Any], Parsed | None]) -> Parsed | None:
    """What `parse` makes of a live file's JSON, or None: no file, too big, not JSON, or
    anything `parse` refuses."""
    try:
        with path.open("rb") as handle:
            raw = handle.read(MAX_BYTES + 1)
        return parse(json.loads(raw)) if len(raw) <= MAX_BYTES else None
    except Exception:  # untrusted: whatever it holds (deep nesting, a huge number) is
        return None  # nothing running, never a crashed projector


def is_fresh(written_at: float, now: float | None = None) -> bool:
    """A live file written within `STALE_SECONDS`: older, its writer stopped (closed or
    killed), or its clock is far off."""
    moment = time.time() if now is None else now
    return -STALE_SECONDS < moment - written_at <= STALE_SECONDS


class LiveFile:
    """One live file's writing, for a heat or a match: when a write is due (a change at
    once, a moving car every MOVING_SECONDS, otherwise the heartbeat), the write itself,
    and its removal when the race is left. A failed write never stops the race: the
    projector is a bonus, the race is not."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.writes = 0
        self._last_at = -math.inf
        self._written = False

    def due(self, *, changed: bool, moved: bool, now: float) -> bool:
        since = now - self._last_at
        return (
            not self._written
            or changed
            or (moved and since >= MOVING_SECONDS)
            or since >= HEARTBEAT_SECONDS
        )

    def write(self, data: Any, now: float) -> bool:
        """Write the file whole (atomically); whether it was written. Not synced to disk:
        it is worth a second of the race, and a sync could hold up a timekeeper's key."""
        try:
            write_text_atomic(self.path, json.dumps(data, sort_keys=True), durable=False)
        except OSError:
            return False
        self._last_at, self._written = now, True
        self.writes += 1
        return True

    def clear(self) -> None:
        with contextlib.suppress(OSError):  # stale within seconds anyway
            self.path.unlink(missing_ok=True)
        self._written = False


def _parse(data: Any) -> LiveHeat | None:
    if not isinstance(data, dict):
        return None
    texts = ("night_id", "heat_id", "racer", "car", "state")
    if not all(is_shown_text(data.get(key)) for key in texts):
        return None
    if data["state"] not in STATES:
        return None
    counts = ("heat_number", "lap", "offtracks")
    if not all(is_count(data.get(key)) for key in counts):
        return None
    numbers = ("time_left", "lap_time", "written_at")
    if not all(is_amount(data.get(key)) for key in numbers):
        return None
    best, limit = data.get("best_lap"), data.get("limit")
    if not (best is None or is_amount(best)) or not (limit is None or is_count(limit)):
        return None
    laps = _laps(data.get("laps", []))
    car_at = data.get("car_at")
    if laps is None or not (car_at is None or is_place(car_at)):
        return None
    fields = {key: data[key] for key in (*texts, *counts, *numbers)}
    return LiveHeat(
        best_lap=best,
        limit=limit,
        laps=laps,
        car_at=None if car_at is None else (float(car_at[0]), float(car_at[1])),
        **fields,
    )


def _laps(value: Any) -> tuple[LiveLap, ...] | None:
    if not isinstance(value, list) or len(value) > MAX_LAPS:
        return None
    laps = []
    for lap in value:
        if not (
            isinstance(lap, dict)
            and set(lap) == {"time_seconds", "penalty_seconds", "offtracks", "counts"}
            and is_amount(lap["time_seconds"])
            and is_amount(lap["penalty_seconds"])
            and is_count(lap["offtracks"])
            and isinstance(lap["counts"], bool)
        ):
            return None
        laps.append(LiveLap(**lap))
    return tuple(laps)


def is_place(value: Any) -> bool:
    """Metres on a track: finite, and within any track's reach."""
    return (
        isinstance(value, list)
        and len(value) == 2
        and all(
            isinstance(v, int | float)
            and not isinstance(v, bool)
            and math.isfinite(v)
            and abs(v) < 10_000
            for v in value
        )
    )


def is_shown_text(value: Any) -> bool:
    """Text shown on the venue's screen: printable, so no escape sequence reaches it."""
    return isinstance(value, str) and len(value) <= MAX_TEXT and value.isprintable()


def is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 1_000_000


def is_amount(value: Any) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value >= 0
    )


class LiveHeatWriter:
    """Writes one heat's progress for the projector: on every change of state, lap,
    off-tracks or best lap at once, otherwise at most every HEARTBEAT_SECONDS; `clear`
    when the heat is left. A failed write never stops the heat: the projector is a bonus,
    the heat is not."""

    def __init__(
        self, path: Path, *, night_id: str, heat_id: str, heat_number: int, racer: str, car: str
    ) -> None:
        self.file = LiveFile(path)
        self.heat = LiveHeat(
            night_id=night_id,
            heat_id=heat_id,
            heat_number=heat_number,
            racer=racer[:MAX_TEXT],
            car=car[:MAX_TEXT],
            state="ready",
            time_left=0.0,
            lap=1,
            lap_time=0.0,
            best_lap=None,
            offtracks=0,
            limit=None,
        )

    @property
    def path(self) -> Path:
        return self.file.path

    @property
    def writes(self) -> int:
        return self.file.writes

    def publish(
        self,
        *,
        state: str,
        time_left: float,
        lap: int,
        lap_time: float,
        best_lap: float | None,
        offtracks: int,
        limit: int | None,
        laps: tuple[LiveLap, ...] = (),
        car_at: tuple[float, float] | None = None,
        now: float | None = None,
    ) -> bool:
        """Write the heat's progress if it changed, its car moved and `MOVING_SECONDS` have
        gone by, or the heartbeat is due; whether it did."""
        moment = time.time() if now is None else now
        last = self.heat
        changed = (last.state, last.lap, last.offtracks, last.best_lap, len(last.laps)) != (
            state,
            lap,
            offtracks,
            best_lap,
            len(laps),
        )
        if not self.file.due(changed=changed, moved=car_at != last.car_at, now=moment):
            return False
        heat = replace(
            last,
            state=state,
            time_left=max(time_left, 0.0),
            lap=lap,
            lap_time=max(lap_time, 0.0),
            best_lap=best_lap,
            offtracks=offtracks,
            limit=limit,
            written_at=moment,
            laps=laps[-MAX_LAPS:],
            car_at=car_at,
        )
        if not self.file.write(asdict(heat), moment):
            return False
        self.heat = heat
        return True

    def clear(self) -> None:
        self.file.clear()

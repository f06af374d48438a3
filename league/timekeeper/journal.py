"""A physical car's heat survives its racer-tui: every input the timekeeper gave, on disk.

A heat is recorded in the league only when it ends. If racer-tui is killed, or the laptop
sleeps for good, in the middle of a physical car's 4 minutes, the laps captured so far
would be lost, and a real car would have to drive its heat again. So the timekeeper writes
each input the heat took (a key or a timer line) to a small file beside the league, and
while the race runs, a heartbeat of how long it has run. Opening the heat again replays
the inputs on a new `TimekeptHeat` (it never reads a clock itself, so a replay is exact)
and stops the clocks where the last heartbeat left them: the heat is back, paused, and
the host starts it again when the car is on the track.

The file is a journal: a header line, then one JSON line per input or heartbeat, appended
with one write each. A key must not wait for the disk: a whole-file atomic rewrite is five
system calls, each a chance for a simulation thread to take the interpreter (the keys'
p95 beside one went from 46 to 69 ms), and an append is one. A process killed mid-write
leaves at most a torn last line, which is ignored; nothing is synced to disk, which a
killed process does not need. Times are seconds since the heat's first input, on its own
timekeeper's clock. A file that cannot be read, or does not replay, is no journal: the
heat starts afresh, as it did before journals.

A physical bracket match (league.timekeeper.match) keeps the same journal: its header says
how many cars it has, and each input line names its car as a fourth item.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO, Protocol

from league.timekeeper.heat import Phase, TimekeeperError, TimekeptHeat
from league.timekeeper.match import TimekeptMatch
from sim.race.head_to_head import MAX_CARS, MIN_CARS
from sim.race.rules import RaceRules

FORMAT = 1
FOLDER = "live-heats"  # beside the projector's live heats: the same life, the same place
# An hour's window (the rules' longest) is 3,600 heartbeats and its inputs.
MAX_LINES = 20_000
MAX_BYTES = 2_000_000
BEAT_SECONDS = 1.0  # how often a running heat notes how long it has run
BEAT = "beat"  # a heartbeat's line: the heat had run until then

# The inputs a heat takes, by name: what the timekeeper's keys and a timer's lines do.
_INPUTS: dict[str, Callable[[TimekeptHeat, float, int | None], str]] = {
    "start_or_pause": lambda heat, at, _: heat.start_or_pause(at),
    "capture": lambda heat, at, _: heat.capture(at),
    "timer_capture": lambda heat, at, _: heat.capture(at, from_timer=True),
    "reset": lambda heat, at, _: heat.reset(at),
    "undo_reset": lambda heat, at, _: heat.undo_reset(),
    "undo_capture": lambda heat, at, _: heat.undo_capture(at),
    "did_not_finish": lambda heat, at, _: heat.did_not_finish(at),
    "strike": lambda heat, at, lap: heat.strike(lap or 0, at),
    "end": lambda heat, at, _: heat.end(at),
}
INPUTS = tuple(_INPUTS)
# A match's inputs: those about one car name it (`car`, its grid index).
_MATCH_INPUTS: dict[str, Callable[[TimekeptMatch, float, int | None, int], str]] = {
    "start_or_pause": lambda match, at, _, __: match.start_or_pause(at),
    "capture": lambda match, at, _, car: match.capture(car, at),
    "reset": lambda match, at, _, car: match.reset(car, at),
    "undo_reset": lambda match, at, _, car: match.undo_reset(car, at),
    "undo_capture": lambda match, at, _, car: match.undo_capture(car, at),
    "retire": lambda match, at, _, car: match.retire(car, at),
    "strike": lambda match, at, lap, car: match.strike(car, lap or 0, at),
    "end": lambda match, at, _, __: match.end(at),
}
MATCH_INPUTS = tuple(_MATCH_INPUTS)

Input = tuple[str, float, int | None, int | None]  # kind, at, lap, car (a match's)


class _Timed(Protocol):
    started_at: str


def journal_path(league_file: Path, heat_id: str) -> Path:
    return league_file.parent / FOLDER / f"{heat_id}.timekeeper.json"


def take_input(heat: TimekeptHeat, kind: str, at: float, lap: int | None = None) -> str:
    """Give `heat` one input; what it says, or TimekeeperError when its phase refuses it."""
    return _INPUTS[kind](heat, at, lap)


def take_match_input(
    match: TimekeptMatch, kind: str, at: float, lap: int | None = None, car: int = 0
) -> str:
    """Give `match` one input (about car `car`, where it is about one); what it says, or
    TimekeeperError when the match refuses it."""
    return _MATCH_INPUTS[kind](match, at, lap, car)


@dataclass
class HeatJournal:
    """The inputs one heat took, appended to `path` as they come."""

    path: Path
    heat_id: str  # a match's: its night's id and its own, "<night id>-W1-1"
    started_at: str = ""  # the heat's own start, wall time (TimekeptHeat.started_at)
    inputs: list[Input] = field(default_factory=list)
    beat: float = 0.0  # how long the heat had been going at the last heartbeat
    cars: int | None = None  # a match's cars; None for a heat's one
    _file: BinaryIO | None = field(default=None, repr=False)

    def took(
        self,
        kind: str,
        at: float,
        heat: _Timed,
        lap: int | None = None,
        car: int | None = None,
    ) -> None:
        """Note an input the heat (or match) has just taken (never one it refused); a
        match's names its car, or 0 for one about every car."""
        if self._file is None and not self.inputs:  # the heat's first input: a new file
            self.started_at = heat.started_at
            header: dict[str, object] = {
                "format": FORMAT,
                "heat_id": self.heat_id,
                "started_at": heat.started_at,
            }
            if self.cars is not None:
                header["cars"] = self.cars
            self._append(header, new=True)
        if self.cars is not None and car is None:
            car = 0
        # Kept whole (JSON writes a float exactly): rounded, a lap captured at 5.01049 s
        # read 5.010 live and 5.011 once the heat was resumed (the host walk).
        self.inputs.append((kind, at, lap, car))
        self.beat = max(self.beat, at)
        self._append([kind, at, lap] if car is None else [kind, at, lap, car])

    def heartbeat(self, at: float) -> None:
        """While the race runs: it ran until `at` (written at most every BEAT_SECONDS)."""
        if self.inputs and at - self.beat >= BEAT_SECONDS:
            self.beat = at
            self._append([BEAT, at, None] if self.cars is None else [BEAT, at, None, 0])

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def forget(self) -> None:
        """The heat was recorded or given up: nothing to resume."""
        self.close()
        self.inputs.clear()
        self.path.unlink(missing_ok=True)

    def _append(self, item: object, *, new: bool = False) -> None:
        file = self._file
        if file is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # Kept open for the heat; unbuffered, so each line is one write.
            file = self._file = self.path.open("wb" if new else "ab", buffering=0)
        file.write(json.dumps(item).encode() + b"\n")


@dataclass(frozen=True)
class Resumed:
    """A heat rebuilt from its journal, stopped where the journal ends."""

    heat: TimekeptHeat
    journal: HeatJournal
    at: float  # the heat's own time where it stopped: later inputs carry on from here
    stopped: bool  # its clocks were running: the replay paused them at `at`

    def accept(self) -> None:
        """Go on with this heat: its journal goes on too, with the pause the replay made."""
        if self.stopped:
            self.journal.took("start_or_pause", self.at, self.heat)


def resume_heat(
    path: Path, heat_id: str, rules: RaceRules, *, floor_seconds: float | None = None
) -> Resumed | None:
    """The heat `heat_id` as its journal left it, or None: no journal, one for another
    heat, one with no input, or one that cannot be read or replayed. `floor_seconds` (the
    heat's, `heat.physical_floor`) holds for the captures still to come: the journal's own
    were taken as they were."""
    journal = _read(path, heat_id)
    if journal is None or not journal.inputs:
        return None
    if journal.cars is not None:
        return None  # a match's journal (`resume_match`)
    heat = TimekeptHeat(rules)
    try:
        for kind, at, lap, _ in journal.inputs:
            take_input(heat, kind, at, lap)
    except TimekeeperError:
        return None  # not what this heat's rules and inputs make: not this heat's journal
    at = max(journal.beat, journal.inputs[-1][1])
    stopped = heat.phase is Phase.RUNNING
    if stopped:
        take_input(heat, "start_or_pause", at)  # stop the clocks where they were last seen
    heat.started_at = journal.started_at or heat.started_at
    heat.floor_seconds = floor_seconds
    return Resumed(heat, journal, at, stopped)


@dataclass(frozen=True)
class ResumedMatch:
    """A match rebuilt from its journal, stopped where the journal ends."""

    match: TimekeptMatch
    journal: HeatJournal
    at: float
    stopped: bool

    def accept(self) -> None:
        if self.stopped:
            self.journal.took("start_or_pause", self.at, self.match)


def resume_match(
    path: Path,
    match_key: str,
    rules: RaceRules,
    cars: int,
    *,
    floor_seconds: float | None = None,
) -> ResumedMatch | None:
    """The match `match_key` (its journal's `heat_id`) as its journal left it, or None, as
    `resume_heat` says."""
    journal = _read(path, match_key)
    if journal is None or not journal.inputs or journal.cars != cars:
        return None
    match = TimekeptMatch(rules, cars)
    try:
        for kind, at, lap, car in journal.inputs:
            take_match_input(match, kind, at, lap, car or 0)
    except TimekeeperError:
        return None
    at = max(journal.beat, journal.inputs[-1][1])
    stopped = match.phase is Phase.RUNNING
    if stopped:
        take_match_input(match, "start_or_pause", at)
    match.started_at = journal.started_at or match.started_at
    match.floor_seconds = floor_seconds
    return ResumedMatch(match, journal, at, stopped)


def _read(path: Path, heat_id: str) -> HeatJournal | None:
    try:
        with path.open("rb") as handle:
            raw = handle.read(MAX_BYTES + 1)
        if len(raw) > MAX_BYTES:
            return None
        lines = raw.split(b"\n")
        if lines[-1].strip():  # torn by a kill mid-write: the lines before it stand
            lines.pop()
        return _parse([json.loads(line) for line in lines if line.strip()], path, heat_id)
    except (OSError, ValueError, TypeError, RecursionError):
        return None


def _parse(items: list[Any], path: Path, heat_id: str) -> HeatJournal | None:
    if not items or len(items) > MAX_LINES:
        return None
    header, *rest = items
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        return None
    if header.get("heat_id") != heat_id or not isinstance(header.get("started_at"), str):
        return None
    cars = header.get("cars")
    if cars is not None and (not _whole(cars) or not MIN_CARS <= cars <= MAX_CARS):
        return None
    kinds = _INPUTS if cars is None else _MATCH_INPUTS
    parsed: list[Input] = []
    last = 0.0
    for item in rest:
        if not isinstance(item, list) or len(item) != (3 if cars is None else 4):
            return None
        kind, at, lap = item[:3]
        car: int | None = None
        if cars is not None:
            if not (_whole(item[3]) and 0 <= item[3] < cars):
                return None
            car = item[3]
        if (kind not in kinds and kind != BEAT) or not _seconds(at) or at < last:
            return None
        if lap is not None and not _whole(lap):
            return None
        last = float(at)
        if kind != BEAT:
            parsed.append((kind, last, lap, car))
    return HeatJournal(path, heat_id, header["started_at"][:40], parsed, last, cars)


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _seconds(value: Any) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and 0.0 <= value <= 86_400.0
    )

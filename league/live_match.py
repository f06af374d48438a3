"""The bracket match racing now, for the venue's projector: as `league.live_heat` does for
a heat, the screen running the match writes where its cars are to a small JSON file
beside the league (`live-heats/<night id>.match.json`), and the night's projector, often
another racer-tui on the venue's screen, reads it. The match reaches the database only
when it is recorded, after its finish.

The same rules as a heat's file: written at once when the running order, a car's laps or
penalty or the race's state change, every `MOVING_SECONDS` while the cars move, at least
every `HEARTBEAT_SECONDS`; a file older than `STALE_SECONDS` is a racer-tui closed or
killed mid-match, so no match is running. It is untrusted input: anything unexpected in
it reads as no match running.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from league.live_heat import (
    FOLDER,
    MAX_TEXT,
    LiveFile,
    is_amount,
    is_count,
    is_fresh,
    is_place,
    is_shown_text,
    read_live_file,
)

SUFFIX = ".match.json"
MOST_CARS = 6  # a head-to-head grid's
STATES = ("running", "over")
INCIDENTS_KEPT = 4  # the newest crashes and overtakes, for the venue to read
INCIDENT_KINDS = ("crash", "overtake")


@dataclass(frozen=True)
class LiveCar:
    """One car of the match as the race view shows it."""

    racer: str  # the racer's display name
    car: str  # the model, or the bundle's file name
    place: int  # in the running order, from 1
    laps: int  # completed
    gap: float | None  # seconds behind the leader; None for the leader, or not known yet
    held_for: str  # why it stands ("crash", "off track", "reversed"), "" when it drives
    finished: bool  # it has completed the race's laps
    at: tuple[float, float] | None = None  # where it is, metres
    heading: float = 0.0  # degrees, counter-clockwise from +x


@dataclass(frozen=True)
class LiveIncident:
    """A crash (`car` ran into `other` from behind) or an overtake (`car` passed `other`);
    the cars by grid index."""

    clock: float
    kind: str  # one of INCIDENT_KINDS
    car: int
    other: int


@dataclass(frozen=True)
class LiveMatch:
    night_id: str
    match_id: str
    title: str  # the round as racers name it ("Final", "Losers' round 2")
    state: str  # one of STATES
    clock: float  # race clock, seconds
    lap_count: int | None  # laps to win; None: a race for the window
    cars: tuple[LiveCar, ...]  # in grid order
    written_at: float = 0.0  # wall clock (time.time()) of the write
    incidents: tuple[LiveIncident, ...] = ()  # the newest last, at most INCIDENTS_KEPT

    def running_order(self) -> list[LiveCar]:
        return sorted(self.cars, key=lambda car: car.place)


def live_match_path(league_file: Path, night_id: str) -> Path:
    return league_file.parent / FOLDER / f"{night_id}{SUFFIX}"


def read_live_match(path: Path, night_id: str, now: float | None = None) -> LiveMatch | None:
    """The match racing now on night `night_id`, or None: no file, a stale one, or one that
    does not hold what a writer writes."""
    match = read_live_file(path, _parse)
    if match is None or match.night_id != night_id or not is_fresh(match.written_at, now):
        return None
    return match


def _parse(data: Any) -> LiveMatch | None:
    if not isinstance(data, dict):
        return None
    texts = ("night_id", "match_id", "title", "state")
    if not all(is_shown_text(data.get(key)) for key in texts) or data["state"] not in STATES:
        return None
    if not all(is_amount(data.get(key)) for key in ("clock", "written_at")):
        return None
    lap_count = data.get("lap_count")
    if not (lap_count is None or is_count(lap_count)):
        return None
    cars = data.get("cars")
    if not isinstance(cars, list) or not 2 <= len(cars) <= MOST_CARS:
        return None
    parsed = [_car(car) for car in cars]
    if any(car is None for car in parsed):
        return None
    incidents = _incidents(data.get("incidents", []), len(cars))
    if incidents is None:
        return None
    return LiveMatch(
        night_id=data["night_id"],
        match_id=data["match_id"],
        title=data["title"],
        state=data["state"],
        clock=float(data["clock"]),
        lap_count=lap_count,
        cars=tuple(car for car in parsed if car is not None),
        written_at=float(data["written_at"]),
        incidents=incidents,
    )


def _incidents(data: Any, cars: int) -> tuple[LiveIncident, ...] | None:
    if not isinstance(data, list) or len(data) > INCIDENTS_KEPT:
        return None
    found = []
    for one in data:
        if not (
            isinstance(one, dict)
            and set(one) == {"clock", "kind", "car", "other"}
            and is_amount(one["clock"])
            and one["kind"] in INCIDENT_KINDS
            and all(is_count(one[key]) and one[key] < cars for key in ("car", "other"))
        ):
            return None
        found.append(LiveIncident(float(one["clock"]), one["kind"], one["car"], one["other"]))
    return tuple(found)


def _car(data: Any) -> LiveCar | None:
    if not isinstance(data, dict):
        return None
    if not all(is_shown_text(data.get(key)) for key in ("racer", "car")):
        return None
    held = data.get("held_for")
    if not (isinstance(held, str) and (held == "" or is_shown_text(held))):
        return None
    if not all(is_count(data.get(key)) for key in ("place", "laps")):
        return None
    gap, at = data.get("gap"), data.get("at")
    if not (gap is None or is_amount(gap)) or not (at is None or is_place(at)):
        return None
    heading = data.get("heading", 0.0)
    if not isinstance(data.get("finished"), bool) or not _angle(heading):
        return None
    return LiveCar(
        racer=data["racer"],
        car=data["car"],
        place=data["place"],
        laps=data["laps"],
        gap=None if gap is None else float(gap),
        held_for=held,
        finished=data["finished"],
        at=None if at is None else (float(at[0]), float(at[1])),
        heading=float(heading),
    )


def _angle(value: Any) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and abs(value) <= 720.0
    )


class LiveMatchWriter:
    """Writes one match's progress for the projector (see the module's docstring);
    `clear` when the match is left. A failed write never stops the race."""

    def __init__(
        self,
        path: Path,
        *,
        night_id: str,
        match_id: str,
        title: str,
        lap_count: int | None,
        racers: Sequence[tuple[str, str]],  # (racer, car) in grid order
    ) -> None:
        self.file = LiveFile(path)
        self.match = LiveMatch(
            night_id=night_id,
            match_id=match_id[:MAX_TEXT],
            title=title[:MAX_TEXT],
            state="running",
            clock=0.0,
            lap_count=lap_count,
            cars=tuple(
                LiveCar(racer[:MAX_TEXT], car[:MAX_TEXT], k + 1, 0, None, "", False)
                for k, (racer, car) in enumerate(racers)
            ),
        )

    @property
    def path(self) -> Path:
        return self.file.path

    def publish(
        self,
        *,
        state: str,
        clock: float,
        cars: Sequence[LiveCar],
        incidents: Sequence[LiveIncident] = (),
        now: float | None = None,
    ) -> bool:
        """Write the match as it stands if it changed, its cars moved and
        `MOVING_SECONDS` have gone by, or the heartbeat is due; whether it did. `cars` in
        grid order, their names as the writer was given them."""
        moment = time.time() if now is None else now
        last = self.match
        named = tuple(
            replace(car, racer=mine.racer, car=mine.car)
            for car, mine in zip(cars, last.cars, strict=True)
        )

        def standing(match_cars: Sequence[LiveCar]) -> list[tuple[Any, ...]]:
            return [(c.place, c.laps, c.held_for, c.finished) for c in match_cars]

        kept = tuple(incidents[-INCIDENTS_KEPT:])
        changed = (
            last.state != state or standing(last.cars) != standing(named) or kept != last.incidents
        )
        moved = [c.at for c in named] != [c.at for c in last.cars]
        if not self.file.due(changed=changed, moved=moved, now=moment):
            return False
        match = replace(
            last, state=state, clock=max(clock, 0.0), cars=named, written_at=moment, incidents=kept
        )
        if not self.file.write(asdict(match), moment):
            return False
        self.match = match
        return True

    def clear(self) -> None:
        self.file.clear()

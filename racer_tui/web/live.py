"""The heat running now, pushed to every viewer of `/live` as server-sent events.

The heat in progress is not in the league until it ends: the screen running it (the race
view, or the timekeeper for a physical car) writes where it is to the night's live-heat
file (`league.live_heat`), and a bracket match's race view to its live-match file
(`league.live_match`). One reader per night polls that file and the night's leader
for every viewer at once, and each viewer's stream sends the newest state when it
changes (and a comment now and then, so proxies keep the connection open).
"""

from __future__ import annotations

import asyncio
import json
import math
from collections.abc import AsyncIterator, Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from league.live_heat import LiveHeat, live_heat_path, read_live_heat
from league.live_match import LiveCar, LiveMatch, live_match_path, read_live_match
from league.nights import Night, standings
from league.report import SCORE_TITLES
from league.store import League
from sim.race.rules import RankingMethod
from sim.tracks.catalog import find_track_by_hash, resolve_track

# The file is read this often while someone watches: with the writer's own interval
# (`league.live_heat.MOVING_SECONDS`), a viewer is at most a quarter-second behind.
POLL_SECONDS = 0.1
# The night's leader changes only when a heat is recorded: looked up this often.
LEADER_SECONDS = 2.0
KEEP_ALIVE_SECONDS = 15.0
KEEP_ALIVE = b": still here\n\n"  # an event-stream comment: no event, the line stays open
# A drawing of the track: its borders as SVG paths in a box this many units wide.
MAP_UNITS = 1000.0


@dataclass(frozen=True)
class Placing:
    """How metres on a track map into the drawing's units (SVG's y grows downwards)."""

    scale: float
    min_x: float
    max_y: float
    margin: float

    def place(self, x: float, y: float) -> tuple[float, float]:
        return (
            round((x - self.min_x) * self.scale + self.margin, 1),
            round((self.max_y - y) * self.scale + self.margin, 1),
        )


@dataclass(frozen=True)
class TrackMap:
    """The night's track as an SVG drawing, and where a place on it is in the drawing."""

    view_box: str
    inner: str  # SVG path data
    outer: str
    placing: Placing

    def place(self, x: float, y: float) -> tuple[float, float]:
        return self.placing.place(x, y)


def track_map(track_hash: str) -> TrackMap | None:
    """The drawing of a track this machine has; None for one it does not."""
    info = find_track_by_hash(track_hash)
    if info is None:
        return None
    track = resolve_track(info.name)
    points = [*track.inner, *track.outer]
    xs, ys = [float(p[0]) for p in points], [float(p[1]) for p in points]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-6)
    margin = MAP_UNITS * 0.03
    placing = Placing((MAP_UNITS - 2 * margin) / span, min(xs), max(ys), margin)

    def path(border: Any) -> str:
        placed = [placing.place(float(x), float(y)) for x, y in border]
        return "M" + " L".join(f"{px:g},{py:g}" for px, py in placed) + " Z"

    width = (max(xs) - min(xs)) * placing.scale + 2 * margin
    height = (max(ys) - min(ys)) * placing.scale + 2 * margin
    return TrackMap(f"0 0 {width:.0f} {height:.0f}", path(track.inner), path(track.outer), placing)


@dataclass(frozen=True)
class Leader:
    racer: str
    score: float


def night_leader(league: League, night: Night, local_models: frozenset[str]) -> Leader | None:
    """The night's first place so far, by the night's own ranking."""
    ranked = standings(league, night, local_models=local_models)
    if not ranked or ranked[0].entry.score is None:
        return None
    return Leader(ranked[0].entry.display_name, ranked[0].entry.score)


def match_json(match: LiveMatch | None, drawing: TrackMap | None) -> dict[str, Any] | None:
    """A bracket match racing now, as `/api/live` gives it: its round, the race clock and
    its cars in grid order, each with its place in the drawing; its newest incidents."""
    if match is None:
        return None

    def car(one: LiveCar) -> dict[str, Any]:
        shown = asdict(one)
        at = one.at
        shown["at"] = None if at is None else list(at)
        shown["on_map"] = None if at is None or drawing is None else list(drawing.place(*at))
        return shown

    return {
        "match_id": match.match_id,
        "title": match.title,
        "state": match.state,
        "clock": match.clock,
        "lap_count": match.lap_count,
        "cars": [car(one) for one in match.cars],
        "incidents": [asdict(one) for one in match.incidents],
    }


def live_json(
    night: Night,
    heat: LiveHeat | None,
    leader: Leader | None,
    drawing: TrackMap | None,
    match: LiveMatch | None = None,
) -> dict[str, Any]:
    """What `/api/live` answers and each event carries: the heat running now, or a bracket
    match (`match`, null between them)."""
    ranking = night.rules.ranking
    shown: dict[str, Any] | None = None
    if heat is not None:
        shown = asdict(heat)
        for private in ("night_id", "written_at"):
            shown.pop(private)
        place = heat.car_at
        shown["car_at"] = None if place is None else list(place)
        shown["car_on_map"] = (
            None if place is None or drawing is None else list(drawing.place(*place))
        )
    gap = None
    # A gap in seconds means something only when a lap is what ranks the night.
    if (
        ranking is RankingMethod.BEST_LAP
        and heat is not None
        and heat.best_lap is not None
        and leader is not None
    ):
        gap = round(heat.best_lap - leader.score, 3)
    return {
        "night": {"id": night.id, "name": night.name, "track": night.track_name},
        "ranking": SCORE_TITLES[ranking],
        "heat": shown,
        "leader": None if leader is None else asdict(leader),
        "gap_to_leader": gap,
        "match": match_json(match, drawing),
    }


class LiveFeed:
    """One night's live heat, read once for every viewer."""

    def __init__(
        self,
        league_file: Path,
        night: Night,
        leader: Callable[[], Leader | None],
        drawing: TrackMap | None,
    ) -> None:
        self.path = live_heat_path(league_file, night.id)
        self.match_path = live_match_path(league_file, night.id)
        self.night = night
        self._leader_of = leader
        self.drawing = drawing
        self.payload = ""
        self._event = b""  # the payload as one event, encoded once for every viewer
        self.version = 0
        self.viewers = 0
        self._changed = asyncio.Condition()
        self._task: asyncio.Task[None] | None = None
        self._leader: Leader | None = None
        self._leader_at = -math.inf

    async def refresh(self) -> None:
        """Read the heat (and, when due, the leader) and tell the viewers if it changed."""
        loop = asyncio.get_running_loop()
        now = loop.time()
        if now - self._leader_at >= LEADER_SECONDS:
            # The database in a worker thread: the event loop keeps serving meanwhile.
            self._leader = await asyncio.to_thread(self._leader_of)
            self._leader_at = now
        heat = read_live_heat(self.path, self.night.id)
        match = read_live_match(self.match_path, self.night.id)
        payload = json.dumps(live_json(self.night, heat, self._leader, self.drawing, match))
        if payload != self.payload:
            self.payload = payload
            self._event = f"data: {payload}\n\n".encode()
            self.version += 1
            async with self._changed:
                self._changed.notify_all()

    async def _poll(self) -> None:
        while self.viewers:
            await self.refresh()
            await asyncio.sleep(POLL_SECONDS)

    async def events(self) -> AsyncIterator[bytes]:
        """One viewer's stream: the newest state whenever it changes."""
        self.viewers += 1
        try:
            if self._task is None or self._task.done():  # the first viewer since none
                await self.refresh()
                self._task = asyncio.create_task(self._poll())
            seen = -1
            while True:
                if self.version != seen:
                    seen = self.version
                    yield self._event
                    continue
                quiet = False
                async with self._changed:
                    if self.version == seen:  # again, now that no refresh can notify unseen
                        try:
                            await asyncio.wait_for(self._changed.wait(), KEEP_ALIVE_SECONDS)
                        except TimeoutError:
                            quiet = True
                if quiet:
                    yield KEEP_ALIVE
        finally:
            self.viewers -= 1

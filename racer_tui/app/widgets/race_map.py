"""The race view's top-down map: the track in braille, with the car, its trail, a ghost,
the start line, off-track marks and the race's boxes or bot cars drawn over it.

Built for 20+ frames per second at a small CPU cost: the track is rasterised once per
size, every row is cached as a Strip, and an update repaints only the rows whose cells
changed (a moving car touches two or three rows per frame, not the whole map).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray
from rich.segment import Segment
from rich.style import Style
from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget

from racer_tui.app.widgets.braille import braille_char, set_dots, styled_runs
from sim.tracks.track import Track

FloatArray = NDArray[np.float64]

# Car glyph by heading, in 45-degree steps counter-clockwise from +x (east).
_ARROWS = "→↗↑↖←↙↓↘"
_GHOST = "◆"
_OFFTRACK = "✕"
_START = "┃"
_OBJECT = "■"  # a box
# A bot car, pointing where it drives (the same steps as the car's arrows).
_BOT_CARS = "▸◥▴◤◂◣▾◢"


@dataclass(frozen=True)
class CarMarker:
    x: float
    y: float
    heading_deg: float


@dataclass(frozen=True)
class RacingCar:
    """A car of a head-to-head race: drawn in its own colour (a Rich colour), dim while it
    is held for a penalty."""

    x: float
    y: float
    heading_deg: float
    colour: str
    held: bool = False


# An overlay cell: its glyph, and a component class of the map or a style of its own.
Mark = tuple[str, str | Style]


class MapProjection:
    """World metres to braille dots for a map of `columns` x `rows` cells, aspect kept."""

    def __init__(self, track: Track, columns: int, rows: int) -> None:
        self.columns, self.rows = columns, rows
        points = np.vstack([track.inner, track.outer])
        self.lo = points.min(axis=0)
        hi = points.max(axis=0)
        span = np.maximum(hi - self.lo, 1e-9)
        self.dots_w, self.dots_h = columns * 2, rows * 4
        self.scale = float(min((self.dots_w - 1) / span[0], (self.dots_h - 1) / span[1]))
        # Centre the drawing in the spare space.
        self.offset = (np.array([self.dots_w - 1, self.dots_h - 1]) - span * self.scale) / 2.0
        self.top = float(hi[1])

    def dots(self, xy: FloatArray) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        xy = np.atleast_2d(xy)
        dx = np.round((xy[:, 0] - self.lo[0]) * self.scale + self.offset[0]).astype(np.int64)
        # Screen rows grow downwards, world y grows upwards.
        dy = np.round((self.top - xy[:, 1]) * self.scale + self.offset[1]).astype(np.int64)
        return np.clip(dx, 0, self.dots_w - 1), np.clip(dy, 0, self.dots_h - 1)

    def cell(self, x: float, y: float) -> tuple[int, int]:
        dx, dy = self.dots(np.array([[x, y]]))
        return int(dx[0]) // 2, int(dy[0]) // 4

    def bits(self, polylines: list[FloatArray]) -> NDArray[np.int32]:
        """Braille bits per cell for the given polylines, densified to dot spacing."""
        grid = np.zeros((self.rows, self.columns), dtype=np.int32)
        for line in polylines:
            if len(line) == 0:
                continue
            dense = _densify(line, 0.5 / self.scale) if len(line) > 1 else line
            dx, dy = self.dots(dense)
            set_dots(grid, dx, dy)
        return grid


def _octant(heading_deg: float) -> int:
    """Which of eight 45-degree steps counter-clockwise from east a heading is nearest."""
    return round((heading_deg % 360.0) / 45.0) % 8


def _arrow(heading_deg: float) -> str:
    return _ARROWS[_octant(heading_deg)]


def _densify(line: FloatArray, spacing: float) -> FloatArray:
    seg = np.hypot(*np.diff(line, axis=0).T)
    cumulative = np.concatenate([[0.0], np.cumsum(seg)])
    count = max(int(cumulative[-1] / max(spacing, 1e-9)) + 1, 2)
    s = np.linspace(0.0, cumulative[-1], count)
    return np.stack(
        [np.interp(s, cumulative, line[:, 0]), np.interp(s, cumulative, line[:, 1])], axis=1
    )


class RaceMap(Widget):
    """Track, car, trail, ghost, start line and off-track marks, redrawn row by row."""

    DEFAULT_CSS = """
    RaceMap {
        height: 1fr;
        min-height: 6;
    }
    RaceMap > .race-map--border { color: $text-muted; }
    RaceMap > .race-map--start { color: $text; text-style: bold; }
    RaceMap > .race-map--trail { color: $accent; }
    RaceMap > .race-map--car { color: $warning; text-style: bold; }
    RaceMap > .race-map--ghost { color: $secondary; }
    RaceMap > .race-map--offtrack { color: $error; text-style: bold; }
    RaceMap > .race-map--object { color: $primary; text-style: bold; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = {
        "race-map--border",
        "race-map--start",
        "race-map--trail",
        "race-map--car",
        "race-map--ghost",
        "race-map--offtrack",
        "race-map--object",
    }

    def __init__(
        self, track: Track | None = None, *, name: str | None = None, id: str | None = None
    ) -> None:
        super().__init__(name=name, id=id)
        self._track = track
        self._projection: MapProjection | None = None
        self._border = np.zeros((0, 0), dtype=np.int32)
        self._start_cells: set[tuple[int, int]] = set()
        self._trail_world: FloatArray = np.zeros((0, 2))
        self._trail = np.zeros((0, 0), dtype=np.int32)
        self._car: CarMarker | None = None
        self._ghost: tuple[float, float] | None = None
        self._offtracks: FloatArray = np.zeros((0, 2))
        self._objects: tuple[tuple[float, float, float], ...] = ()
        self._objects_are_cars = False
        self._cars: tuple[RacingCar, ...] = ()
        self._marks: dict[tuple[int, int], Mark] = {}  # (col, row) -> glyph, class or style
        self._rows: list[Strip | None] = []
        self.frames_drawn = 0  # rows of the car repainted: one per displayed frame

    # --- public API ------------------------------------------------------------------

    @property
    def track(self) -> Track | None:
        return self._track

    def set_track(self, track: Track | None) -> None:
        self._track = track
        self._trail_world = np.zeros((0, 2))
        self._offtracks = np.zeros((0, 2))
        self._car = None
        self._ghost = None
        self._rebuild()

    def show(
        self,
        car: CarMarker | None,
        trail: FloatArray | None = None,
        ghost: tuple[float, float] | None = None,
        offtracks: FloatArray | None = None,
        objects: tuple[tuple[float, float, float], ...] = (),
        *,
        objects_are_cars: bool = False,
        cars: tuple[RacingCar, ...] = (),
    ) -> None:
        """Move the car and overlays (`objects`: the race's boxes or, `objects_are_cars`,
        bot cars: x, y and heading in degrees each; `cars`: a head-to-head race's, the
        first drawn on top); repaints only the rows that change."""
        self._car = car
        self._cars = cars
        self._ghost = ghost
        self._objects = objects
        self._objects_are_cars = objects_are_cars
        if trail is not None:
            self._trail_world = np.asarray(trail, dtype=np.float64).reshape(-1, 2)
        if offtracks is not None:
            self._offtracks = np.asarray(offtracks, dtype=np.float64).reshape(-1, 2)
        if self._projection is None:
            return
        old_trail, old_marks = self._trail, self._marks
        self._trail = self._projection.bits([self._trail_world])
        self._marks = self._overlay_marks()
        changed = set(np.flatnonzero((old_trail != self._trail).any(axis=1)).tolist())
        for cell in old_marks.keys() ^ self._marks.keys():
            changed.add(cell[1])
        for cell in old_marks.keys() & self._marks.keys():
            if old_marks[cell] != self._marks[cell]:
                changed.add(cell[1])
        for row in changed:
            self._rows[row] = None
            self.refresh(Region(0, row, self._projection.columns, 1))

    # --- rendering -------------------------------------------------------------------

    def on_resize(self) -> None:
        self._rebuild()

    def _rebuild(self) -> None:
        width, height = self.size.width, self.size.height
        track = self._track
        if track is None or width < 2 or height < 2:
            self._projection = None
            self._rows = [None] * max(height, 0)
            self.refresh()
            return
        projection = MapProjection(track, width, height)
        self._projection = projection
        self._border = projection.bits([track.inner, track.outer])
        start = np.linspace(track.inner[0], track.outer[0], 12)
        cols, rows = projection.dots(start)
        self._start_cells = set(zip((cols // 2).tolist(), (rows // 4).tolist(), strict=True))
        self._trail = projection.bits([self._trail_world])
        self._marks = self._overlay_marks()
        self._rows = [None] * height
        self.refresh()

    def _overlay_marks(self) -> dict[tuple[int, int], Mark]:
        projection = self._projection
        marks: dict[tuple[int, int], Mark] = {}
        if projection is None:
            return marks
        for x, y in self._offtracks:
            marks[projection.cell(float(x), float(y))] = (_OFFTRACK, "race-map--offtrack")
        for x, y, heading in self._objects:
            glyph = _OBJECT
            if self._objects_are_cars:
                glyph = _BOT_CARS[_octant(heading)]
            marks[projection.cell(x, y)] = (glyph, "race-map--object")
        if self._ghost is not None:
            marks[projection.cell(*self._ghost)] = (_GHOST, "race-map--ghost")
        for racing in reversed(self._cars):  # the leader last: on top where cars meet
            style = Style(color=racing.colour, bold=not racing.held, dim=racing.held)
            marks[projection.cell(racing.x, racing.y)] = (_arrow(racing.heading_deg), style)
        car = self._car
        if car is not None:
            marks[projection.cell(car.x, car.y)] = (_arrow(car.heading_deg), "race-map--car")
        return marks

    def render_line(self, y: int) -> Strip:
        if self._projection is None or y >= len(self._rows):
            if y == 0 and self._track is None:
                return Strip([Segment("Choose a track.", Style(dim=True))])
            return Strip.blank(self.size.width)
        cached = self._rows[y]
        if cached is None:
            cached = self._render_row(y)
            self._rows[y] = cached
        if self._car is not None and self._projection.cell(self._car.x, self._car.y)[1] == y:
            self.frames_drawn += 1
        return cached

    def _render_row(self, y: int) -> Strip:
        projection = self._projection
        assert projection is not None
        styles = {name: self.get_component_rich_style(name) for name in self.COMPONENT_CLASSES}
        base = self.rich_style
        border, trail = self._border[y], self._trail[y]
        cells: list[tuple[str, Style | None]] = []
        for x in range(projection.columns):
            mark = self._marks.get((x, y))
            if mark is not None:
                glyph, style = mark
                cells.append((glyph, styles[style] if isinstance(style, str) else style))
            elif trail[x]:
                cells.append((braille_char(int(trail[x] | border[x])), styles["race-map--trail"]))
            elif (x, y) in self._start_cells:
                cells.append((_START, styles["race-map--start"]))
            elif border[x]:
                cells.append((braille_char(int(border[x])), styles["race-map--border"]))
            else:
                cells.append((" ", base))
        segments = styled_runs(cells)
        return Strip(segments, projection.columns)

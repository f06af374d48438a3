"""The Coach view's map: the track in braille with the limit lap's line, and the car's lap
over it coloured by the time each sector loses; the worst sectors and the chosen one are
named where they are.

The map is still (a lap already driven), so it is drawn whole once per size or choice.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray
from rich.style import Style
from textual.strip import Strip
from textual.widget import Widget

from racer_tui.app.widgets.braille import braille_char, styled_runs
from racer_tui.app.widgets.race_map import MapProjection

if TYPE_CHECKING:  # the coach's numpy and osqp load when a lap is coached, not with the app
    from sim.coach.lap_analysis import SectorReport
    from sim.garage.coach_session import Coaching


# A sector's loss, as a share of the limit lap's time through it, that turns its colour.
SOME_LOSS = 0.10
MUCH_LOSS = 0.30
LOSS_CLASSES = ("coach-map--good", "coach-map--some", "coach-map--much")
NAMED_SECTORS = 3  # the worst sectors are named on the map (and the chosen one)


def loss_class(report: SectorReport) -> int:
    """0 (little lost), 1 (some) or 2 (much): the sector's colour on the map."""
    share = report.lost / max(report.limit_seconds, 1e-6)
    return 2 if share >= MUCH_LOSS else 1 if share >= SOME_LOSS else 0


class CoachMap(Widget):
    """A coached lap on its track; `choose(i)` picks the sector shown in reverse."""

    DEFAULT_CSS = """
    CoachMap { height: 1fr; min-height: 6; }
    CoachMap > .coach-map--border { color: $text-muted; }
    CoachMap > .coach-map--line { color: $secondary; }
    CoachMap > .coach-map--good { color: $success; }
    CoachMap > .coach-map--some { color: $warning; }
    CoachMap > .coach-map--much { color: $error; }
    CoachMap > .coach-map--label { text-style: bold; }
    CoachMap > .coach-map--chosen { text-style: bold reverse; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = {
        "coach-map--border",
        "coach-map--line",
        *LOSS_CLASSES,
        "coach-map--label",
        "coach-map--chosen",
    }

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self._coaching: Coaching | None = None
        self._chosen: int | None = None
        self._lines: list[Strip] | None = None

    @property
    def coaching(self) -> Coaching | None:
        return self._coaching

    def show(self, coaching: Coaching | None) -> None:
        self._coaching = coaching
        self._chosen = None
        self._redraw()

    def choose(self, sector: int | None) -> None:
        """Show sector number `sector` (an index into the report's sectors) in reverse."""
        if sector != self._chosen:
            self._chosen = sector
            self._redraw()

    def _redraw(self) -> None:
        self._lines = None
        self.refresh()

    def on_resize(self) -> None:
        self._redraw()

    def render_line(self, y: int) -> Strip:
        if self._lines is None:
            self._lines = self._draw()
        if y < len(self._lines):
            return self._lines[y]
        return Strip.blank(self.size.width)

    # --- drawing ---------------------------------------------------------------------------

    def _draw(self) -> list[Strip]:
        width, height = self.size.width, self.size.height
        coaching = self._coaching
        if coaching is None or width < 4 or height < 2:
            return []
        styles = {name: self.get_component_rich_style(name) for name in self.COMPONENT_CLASSES}
        track = coaching.track
        projection = MapProjection(track, width, height)
        border = projection.bits([track.inner, track.outer])
        line = projection.bits([coaching.limit.points])
        car, car_class, chosen = self._car_cells(projection)
        labels = self._labels(projection)
        lines = []
        for row in range(height):
            cells: list[tuple[str, Style | None]] = []
            for col in range(width):
                label = labels.get((col, row))
                if label is not None:
                    char, is_chosen = label
                    kind = "coach-map--chosen" if is_chosen else "coach-map--label"
                    cells.append((char, styles[kind]))
                elif car[row, col]:
                    style = styles[LOSS_CLASSES[max(int(car_class[row, col]), 0)]]
                    if chosen[row, col]:
                        style += styles["coach-map--chosen"]
                    cells.append((braille_char(int(car[row, col])), style))
                elif line[row, col]:
                    cells.append((braille_char(int(line[row, col])), styles["coach-map--line"]))
                elif border[row, col]:
                    cells.append((braille_char(int(border[row, col])), styles["coach-map--border"]))
                else:
                    cells.append((" ", self.rich_style))
            lines.append(Strip(styled_runs(cells), width))
        return lines

    def _car_cells(
        self, projection: MapProjection
    ) -> tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.bool_]]:
        """Braille bits of the car's path per cell, each cell's colour (the worst loss class
        of the sectors drawn in it) and whether the chosen sector passes there."""
        coaching = self._coaching
        assert coaching is not None
        report, path = coaching.report, coaching.path
        sector_of_row = report.trace.sector_index([item.sector for item in report.sectors])
        classes = np.array([loss_class(item) for item in report.sectors])
        bits = np.zeros((projection.rows, projection.columns), dtype=np.int32)
        colour = np.full(bits.shape, -1, dtype=np.int32)
        chosen = np.zeros(bits.shape, dtype=bool)
        xy = np.stack([path.x, path.y], axis=1)
        for index in range(len(report.sectors)):
            rows = np.flatnonzero(sector_of_row == index)
            if len(rows) == 0:
                continue
            # One row before and after, so the sectors join up.
            rows = np.arange(max(rows[0] - 1, 0), min(rows[-1] + 2, len(xy)))
            sector_bits = projection.bits([xy[rows]])
            drawn = sector_bits != 0
            bits |= sector_bits
            colour[drawn] = np.maximum(colour[drawn], int(classes[index]))
            if index == self._chosen:
                chosen |= drawn
        return bits, colour, chosen

    def _labels(self, projection: MapProjection) -> dict[tuple[int, int], tuple[str, bool]]:
        """Cells of the names of the worst sectors and the chosen one, each at the middle of
        its sector on the centre line, left out where it would cover another name."""
        coaching = self._coaching
        assert coaching is not None
        sectors = coaching.report.sectors
        ranked = sorted(range(len(sectors)), key=lambda i: sectors[i].lost, reverse=True)
        named = ranked[:NAMED_SECTORS]
        if self._chosen is not None and self._chosen not in named:
            named = [self._chosen, *named]
        centre = coaching.track.centerline
        cells: dict[tuple[int, int], tuple[str, bool]] = {}
        for index in named:
            sector = sectors[index].sector
            middle = centre.point_at(np.array([0.5 * (sector.start + sector.end)]))[0]
            col, row = projection.cell(float(middle[0]), float(middle[1]))
            name = sector.name
            col = min(max(col - len(name) // 2, 0), projection.columns - len(name))
            spots = [(col + i, row) for i in range(len(name))]
            if any(spot in cells for spot in spots):
                continue
            for spot, char in zip(spots, name, strict=True):
                cells[spot] = (char, index == self._chosen)
        return cells

"""The race map draws the car where it is and repaints only the rows that change."""

from __future__ import annotations

import numpy as np
from textual.app import App, ComposeResult

from racer_tui.app.widgets.race_map import CarMarker, MapProjection, RaceMap
from sim.tracks.catalog import resolve_track


class MapApp(App[None]):
    def __init__(self) -> None:
        super().__init__()
        self.track = resolve_track("beginner-oval")

    def compose(self) -> ComposeResult:
        yield RaceMap(self.track)


def _screen_text(app: App[None]) -> list[str]:
    view = app.query_one(RaceMap)
    return [view.render_line(y).text for y in range(view.size.height)]


async def test_the_car_arrow_appears_in_the_cell_of_its_position() -> None:
    app = MapApp()
    async with app.run_test(size=(60, 20)) as pilot:
        view = app.query_one(RaceMap)
        await pilot.pause()
        x, y = (float(v) for v in app.track.center[10])
        view.show(CarMarker(x, y, heading_deg=90.0))
        await pilot.pause()
        col, row = MapProjection(app.track, view.size.width, view.size.height).cell(x, y)
        assert _screen_text(app)[row][col] == "↑"
        view.show(CarMarker(x, y, heading_deg=180.0))
        assert _screen_text(app)[row][col] == "←"


async def test_moving_the_car_repaints_only_the_rows_it_touches() -> None:
    app = MapApp()
    async with app.run_test(size=(60, 20)) as pilot:
        view = app.query_one(RaceMap)
        await pilot.pause()
        projection = MapProjection(app.track, view.size.width, view.size.height)
        x, y = (float(v) for v in app.track.center[0, :2])
        view.show(CarMarker(x, y, 0.0))
        await pilot.pause()
        before = list(view._rows)
        assert all(strip is not None for strip in before)
        y2 = y + 0.6  # a couple of rows further up the map
        view.show(CarMarker(x, y2, 0.0))
        invalidated = {i for i, strip in enumerate(view._rows) if strip is None}
        assert invalidated == {projection.cell(x, y)[1], projection.cell(x, y2)[1]}


async def test_trail_ghost_and_offtrack_marks_are_drawn() -> None:
    app = MapApp()
    async with app.run_test(size=(80, 24)) as pilot:
        view = app.query_one(RaceMap)
        await pilot.pause()
        centre = app.track.center[:, :2]
        view.show(
            CarMarker(float(centre[40, 0]), float(centre[40, 1]), 0.0),
            trail=centre[:40],
            ghost=(float(centre[60, 0]), float(centre[60, 1])),
            offtracks=np.array([app.track.outer[20] + 0.3]),
        )
        await pilot.pause()
        text = "\n".join(_screen_text(app))
        assert "◆" in text
        assert "✕" in text
        assert "┃" in text  # the start line


async def test_a_map_without_a_track_asks_for_one() -> None:
    class Empty(App[None]):
        def compose(self) -> ComposeResult:
            yield RaceMap()

    app = Empty()
    async with app.run_test(size=(40, 10)) as pilot:
        await pilot.pause()
        assert "Choose a track." in app.query_one(RaceMap).render_line(0).text

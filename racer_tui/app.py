"""The racer-tui Textual app. For now: the track browser with reference laps."""

from __future__ import annotations

import math
from typing import ClassVar

from rich.text import Text
from textual import work
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.widgets import DataTable, Footer, Header, Static

from racer_tui.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.widgets.track_map import TrackMap
from sim.race.rules import DEFAULT_RULES
from sim.reference_driver import reference_lap
from sim.track import Track, TrackError
from sim.track_catalog import TrackInfo, list_tracks, resolve_track


class RacerTuiApp(App[int]):
    """Browse tracks: facts, a map, and the reference driver's lap time."""

    TITLE = "racer-tui"
    SUB_TITLE = "tracks"
    CSS = """
    #tracks { width: 2fr; min-width: 40; }
    #detail { width: 3fr; padding: 0 1; }
    #facts { height: auto; margin-bottom: 1; }
    """
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("r", "race", "Race the reference driver"),
        Binding("q", "quit", "Quit"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self._infos: list[TrackInfo] = []

    def compose(self) -> ComposeResult:
        yield Header()
        with Horizontal():
            yield DataTable(id="tracks", cursor_type="row")
            with Vertical(id="detail"):
                yield Static(id="facts")
                yield TrackMap(id="map")
        yield Footer()

    def on_mount(self) -> None:
        table = self.query_one("#tracks", DataTable)
        table.add_columns("track", "length", "width")
        self._infos = list_tracks()
        for info in self._infos:
            # Track names come from files: Text keeps them plain text, never markup.
            table.add_row(Text(info.name), f"{info.length_m:.1f} m", f"{info.width_m:.2f} m")
        table.focus()

    def action_race(self) -> None:
        track = self.query_one("#map", TrackMap).track
        if track is None:
            self.notify("Choose a track first.", severity="warning")
            return
        setup = RaceSetup(track=track, rules=DEFAULT_RULES, racer="reference driver")
        self.push_screen(RaceScreen(setup))

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self._infos):
            self._show(self._infos[event.cursor_row])

    def _show(self, info: TrackInfo) -> None:
        try:
            track = resolve_track(info.name)
        except TrackError as exc:
            self.query_one("#facts", Static).update(Text(str(exc), style="red"))
            return
        self.query_one("#map", TrackMap).track = track
        self._update_facts(track, lap_text="reference lap: timing...")
        self._time_reference_lap(track)

    def _update_facts(self, track: Track, lap_text: str) -> None:
        facts = Text()
        facts.append(track.name, style="bold")
        facts.append(f"\n{track.description}\n" if track.description else "\n")
        facts.append(f"{track.length:.2f} m, {track.width:.3f} m wide, {track.direction}\n")
        facts.append(lap_text)
        self.query_one("#facts", Static).update(facts)

    @work(thread=True, exclusive=True, group="reference-lap")
    def _time_reference_lap(self, track: Track) -> None:
        lap = reference_lap(track)
        text = (
            f"reference lap: {lap.lap_time:.3f} s"
            if not math.isnan(lap.lap_time)
            else f"reference lap: {lap.status}"
        )
        self.call_from_thread(self._lap_timed, track, text)

    def _lap_timed(self, track: Track, text: str) -> None:
        current = self.query_one("#map", TrackMap).track
        if current is track:
            self._update_facts(track, text)


def run_app() -> int:
    RacerTuiApp().run()
    return 0

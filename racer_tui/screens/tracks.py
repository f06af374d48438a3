"""The tracks: built-in and imported, each with its facts, a map and the reference lap time.

The reference lap (the no-learning driver at the grip limit) is timed in a worker, so moving
through the list stays instant.
"""

from __future__ import annotations

import math
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import DataTable, Static

from racer_tui.screens.base import ModelAdded, RacerScreen
from racer_tui.screens.model_editor import ModelEditorScreen
from racer_tui.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.widgets.footer import RacerFooter
from racer_tui.widgets.section_header import SectionHeader
from racer_tui.widgets.table_fill import fill_table
from racer_tui.widgets.track_map import TrackMap
from sim.race.rules import DEFAULT_RULES
from sim.reference_driver import reference_lap
from sim.track import Track, TrackError
from sim.track_catalog import TrackInfo, list_tracks, resolve_track


class ReferenceLapTimed(Message):
    def __init__(self, track: Track, text: str) -> None:
        super().__init__()
        self.track = track
        self.text = text


class TracksScreen(RacerScreen[None]):
    """Browse tracks: facts, a map, and the reference driver's lap time."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("r", "race", "Race the reference driver", tooltip="A 4-minute time trial"),
        Binding("n", "new_model", "New model here", tooltip="The model editor, on this track"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self._infos: list[TrackInfo] = []
        self._lap_texts: dict[str, str] = {}  # track content hash -> reference lap line

    def compose(self) -> ComposeResult:
        yield SectionHeader("tracks")
        with Horizontal(id="tracks-body"):
            yield DataTable(id="tracks", cursor_type="row", zebra_stripes=True)
            with Vertical(id="track-detail"):
                yield Static(id="track-facts")
                yield TrackMap(id="track-map")
        yield RacerFooter()

    def on_mount(self) -> None:
        self._infos = list_tracks()
        rows: list[list[str | Text]] = [
            # Track names come from files: Text keeps them plain text, never markup.
            [Text(info.name), f"{info.length_m:.1f} m", f"{info.width_m:.2f} m"]
            for info in self._infos
        ]
        fill_table(self.query_one("#tracks", DataTable), ["track", "length", "width"], rows)
        count = len(self._infos)
        self.query_one(SectionHeader).set_context(f"{count} tracks")

    @property
    def track(self) -> Track | None:
        return self.query_one("#track-map", TrackMap).track

    def action_race(self) -> None:
        track = self.track
        if track is None:
            self.notify("Choose a track first.", severity="warning")
            return
        setup = RaceSetup(track=track, rules=DEFAULT_RULES, racer="reference driver")
        self.app.push_screen(RaceScreen(setup))

    def action_new_model(self) -> None:
        track = self.track
        if track is None:
            self.notify("Choose a track first.", severity="warning")
            return
        self.app.push_screen(ModelEditorScreen(track=track.name), self._model_created)

    def _model_created(self, name: str | None) -> None:
        if name is not None:
            self.post_message(ModelAdded(name))

    @on(DataTable.RowHighlighted, "#tracks")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self._infos):
            self._show(self._infos[event.cursor_row])

    def _show(self, info: TrackInfo) -> None:
        try:
            track = resolve_track(info.name)
        except TrackError as exc:
            self.query_one("#track-facts", Static).update(Text(str(exc), style="red"))
            return
        self.query_one("#track-map", TrackMap).track = track
        cached = self._lap_texts.get(track.content_hash)
        self._update_facts(track, cached or "reference lap: timing…")
        if cached is None:
            self._time_reference_lap(track)

    def _update_facts(self, track: Track, lap_text: str) -> None:
        facts = Text()
        facts.append(track.name, style="bold")
        facts.append(f"\n{track.description}\n" if track.description else "\n")
        facts.append(f"{track.length:.2f} m, {track.width:.3f} m wide, {track.direction}\n")
        facts.append(lap_text)
        self.query_one("#track-facts", Static).update(facts)

    @work(thread=True, exclusive=True, group="reference-lap", exit_on_error=False)
    def _time_reference_lap(self, track: Track) -> None:
        lap = reference_lap(track)
        text = (
            f"reference lap: {lap.lap_time:.3f} s"
            if not math.isnan(lap.lap_time)
            else f"reference lap: {lap.status}"
        )
        self.post_message(ReferenceLapTimed(track, text))

    def on_reference_lap_timed(self, message: ReferenceLapTimed) -> None:
        self._lap_texts[message.track.content_hash] = message.text
        if self.track is message.track:
            self._update_facts(message.track, message.text)

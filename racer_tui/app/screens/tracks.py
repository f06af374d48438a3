"""The tracks: built-in, AWS DeepRacer's official ones by release year, and imported ones,
each with its facts, a map and the reference lap time; a search box narrows the list.

The reference lap (the no-learning driver at the grip limit) is timed in a worker, so moving
through the list stays instant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import DataTable, Input, Static

from racer_tui.app.jobs import sentence
from racer_tui.app.screens.base import ModelAdded, RacerScreen
from racer_tui.app.screens.dialogs import ImportRequest, PathNameDialog
from racer_tui.app.screens.model_editor import ModelEditorScreen
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.widgets.track_label import track_label
from racer_tui.app.widgets.track_map import TrackMap
from racer_tui.app.words import in_app_words
from sim.coach.limit_lap import limit_lap
from sim.foundation.plural import counted
from sim.physics.reference_driver import reference_lap
from sim.race.rules import DEFAULT_RULES
from sim.tracks.catalog import (
    TrackInfo,
    import_problem,
    import_track,
    list_tracks,
    resolve_track,
)
from sim.tracks.track import Track, TrackError

# Room for a console name in the list at 80 columns; the facts pane shows it whole.
_LABEL_CELLS = 23
_HEADING = "group:"  # row keys of the group headings, which are not tracks


@dataclass
class ReferenceLapTimed(Message):
    track: Track
    text: str


class TracksScreen(RacerScreen[None]):
    """Browse tracks: facts, a map, and the reference driver's lap time."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("r", "race", "Race the reference driver", tooltip="A 4-minute time trial"),
        Binding("n", "new_model", "New model here", tooltip="The model editor, on this track"),
        Binding("slash", "search", "Search", tooltip="Narrow the list by name or console name"),
        Binding("i", "import_track", "Import", tooltip="A DeepRacer track file (.npy)"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self._infos: list[TrackInfo] = []  # every track the app can race
        self._rows: list[TrackInfo | None] = []  # the table's rows: None for a heading
        self._lap_texts: dict[str, str] = {}  # track content hash -> reference lap line

    def compose(self) -> ComposeResult:
        yield SectionHeader("tracks")
        with Horizontal(id="tracks-body"):
            with Vertical(id="tracks-list"):
                yield Input(placeholder="/ search name or console name", id="track-search")
                yield FittedTable(id="tracks", cursor_type="row")
            with Vertical(id="track-detail"):
                yield Static(id="track-facts")
                yield TrackMap(id="track-map")
        yield RacerFooter()

    def on_mount(self) -> None:
        # The straight test road cannot be raced or lapped; `racer-tui tracks list` shows it.
        self._infos = _raceable_tracks()
        self._fill("")
        self.query_one("#tracks", DataTable).focus()

    def _fill(self, search: str) -> None:
        needle = search.casefold().strip()
        shown = [
            info
            for info in self._infos
            if needle in info.name.casefold() or needle in info.console_name.casefold()
        ]
        self._rows = []
        cells: list[list[str | Text]] = []
        for heading, group in _groups(shown):
            self._rows.append(None)
            cells.append([Text(f"{heading} ({len(group)})", style="bold"), ""])
            for info in group:
                self._rows.append(info)
                cells.append([track_label(info, _LABEL_CELLS), f"{info.length_m:.1f}"])
        table = self.query_one("#tracks", DataTable)
        fill_table(table, [Col("track", keep=0, shrink_to=12, collapses=False), "m"], cells)
        total = len(self._infos)
        context = (
            counted(total, "track") if not needle else f"{len(shown)} of {counted(total, 'track')}"
        )
        self.query_one(SectionHeader).set_context(context)
        if not shown:
            self.query_one("#track-map", TrackMap).track = None  # nothing chosen: r races nothing
            self.query_one("#track-facts", Static).update(
                Text(f"No track matches {search.strip()!r}; Esc clears the search.")
            )
            return
        # Start on the first track, not on its group's heading.
        table.move_cursor(row=1)

    def action_search(self) -> None:
        self.query_one("#track-search", Input).focus()

    @on(Input.Changed, "#track-search")
    def _search_changed(self, event: Input.Changed) -> None:
        self._fill(event.value)

    @on(Input.Submitted, "#track-search")
    def _search_done(self) -> None:
        self.query_one("#tracks", DataTable).focus()

    def key_escape(self) -> None:
        search = self.query_one("#track-search", Input)
        if search.has_focus or search.value:
            search.value = ""
            self.query_one("#tracks", DataTable).focus()

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

    def action_import_track(self) -> None:
        self.app.push_screen(TrackImportDialog(_import_requested), self._imported)

    def _imported(self, info: TrackInfo | None) -> None:
        if info is not None:
            self.show_imported(info)

    def show_imported(self, info: TrackInfo) -> None:
        self.notify(
            f"Imported {info.name}."
            if info.kind == "imported"
            else f"{info.title} is already here; nothing was copied.",
            markup=False,
        )
        self._infos = _raceable_tracks()
        search = self.query_one("#track-search", Input)
        with search.prevent(Input.Changed):  # its handler would refill after the move below
            search.value = ""
        self._fill("")
        names = [row.name if row is not None else None for row in self._rows]
        if info.name in names:
            self.query_one("#tracks", DataTable).move_cursor(row=names.index(info.name))

    def _model_created(self, name: str | None) -> None:
        if name is not None:
            self.post_message(ModelAdded(name))

    @on(DataTable.RowHighlighted, "#tracks")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self._rows):
            info = self._rows[event.cursor_row]
            if info is not None:  # a heading keeps the track shown
                self._show(info)

    def _show(self, info: TrackInfo) -> None:
        try:
            track = resolve_track(info.name)
        except TrackError as exc:
            self.query_one("#track-facts", Static).update(Text(str(exc), style="red"))
            return
        self.query_one("#track-map", TrackMap).track = track
        cached = self._lap_texts.get(track.content_hash)
        self._update_facts(track, cached or "limit and reference laps: working them out…")
        if cached is None:
            self._time_laps(track)

    def _update_facts(self, track: Track, lap_text: str) -> None:
        info = next((i for i in self._infos if i.name == track.name), None)
        facts = Text()
        if info is not None and info.console_name:
            facts.append(info.console_name, style="bold")
            facts.append(f"\n{track.name}, AWS DeepRacer")
            facts.append(f", released {info.release_date}\n" if info.release_date else "\n")
        else:
            facts.append(track.name, style="bold")
            facts.append(f"\n{track.description}\n" if track.description else "\n")
        facts.append(f"{track.length:.2f} m, {track.width:.3f} m wide, {track.direction}\n")
        facts.append(lap_text)
        self.query_one("#track-facts", Static).update(facts)

    @work(thread=True, exclusive=True, group="reference-lap", exit_on_error=False)
    def _time_laps(self, track: Track) -> None:
        """The limit laps (the fastest racer-tui's car can drive) and the reference driver's
        lap, in a worker: a few tenths of a second, more on a long track."""
        limit = limit_lap(track)
        lap = reference_lap(track)
        reference = (
            f"reference lap: {lap.lap_time:.3f} s"
            if not math.isnan(lap.lap_time)
            else f"reference lap: {lap.status}"
        )
        text = (
            f"limit lap: {limit.flying_seconds:.3f} s flying, "
            f"{limit.standing_seconds:.3f} s from a standing start\n{reference}"
        )
        self.post_message(ReferenceLapTimed(track, text))

    def on_reference_lap_timed(self, message: ReferenceLapTimed) -> None:
        self._lap_texts[message.track.content_hash] = message.text
        if self.track is message.track:
            self._update_facts(message.track, message.text)


def _raceable_tracks() -> list[TrackInfo]:
    """Every track the section lists (not the straight test road, which has no laps)."""
    return [info for info in list_tracks() if info.lappable]


def _import_requested(request: ImportRequest) -> TrackInfo:
    """Run by the import dialog, in its thread: the file is copied in under its name."""
    return import_track(Path(request.path).expanduser(), request.name)


class TrackImportDialog(PathNameDialog[TrackInfo]):
    """A DeepRacer .npy track file and optionally the name to keep it under; the file is
    read and checked, and the name too, before the dialog closes."""

    TITLE = "Import a track"
    BODY = (
        "A DeepRacer track file (.npy, as the simulator's routes folder keeps them). "
        "→ completes a path."
    )
    PATH_PLACEHOLDER = "path, e.g. ~/Downloads/my_track.npy"
    NAME_PLACEHOLDER = "track name (empty: the file's name)"

    def problem(self, path: str, name: str | None) -> str | None:
        if not path:
            return "Give the path of a DeepRacer track file (.npy)."
        try:
            is_file = Path(path).expanduser().is_file()
        except (OSError, RuntimeError) as error:  # an unknown ~user, a folder it may not read
            return f"{path} cannot be read ({error}); check the path."
        if not is_file:
            return f"{path} is not a file; check the path (→ completes it)."
        problem = import_problem(Path(path).expanduser(), name)
        return None if problem is None else sentence(in_app_words(problem))


def _groups(infos: list[TrackInfo]) -> list[tuple[str, list[TrackInfo]]]:
    """Built-in, then official by release year (the console's never-listed last), then
    imported: the list's order, with a heading for each run of one group."""
    groups: list[tuple[str, list[TrackInfo]]] = []
    for info in infos:
        heading = _heading(info)
        if not groups or groups[-1][0] != heading:
            groups.append((heading, []))
        groups[-1][1].append(info)
    return groups


def _heading(info: TrackInfo) -> str:
    if info.kind == "official":
        return f"Official {info.release_date[:4]}" if info.release_date else "Official, unlisted"
    return "Built-in" if info.kind == "built-in" else "Imported"

"""Races: a time trial of any trained model (or the reference driver) on any track, live.

The races run this session are listed best first (the league's one ranking order), and any
of them can be replayed, and a trained model's race can be submitted to the league (u):
it is recorded with its trace under the racer's name, asked once (see league_submit), and
marked so it is not submitted twice. A new race on a track brings the best lap so far on
that track as a ghost, and the gap to the session's leader there.

Below them, the races recorded in the league (`--record`, league nights, other racers'
synced races), newest first: any of them with a trace on this machine replays from it
(`replay_recorded_race`, which the leaderboard uses too).
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.screen import Screen
from textual.widgets import Button, DataTable, Label, Select, Static

from league.errors import LeagueError
from league.opening import open_league
from league.races import (
    RaceReplay,
    RecordedRace,
    best_lap_race,
    race_replay,
    race_result,
    recent_races,
)
from league.ranking import rank
from racer_tui.app.screens.base import RacerScreen
from racer_tui.app.screens.head_to_head_dialog import HeadToHeadDialog, HeadToHeadRequest
from racer_tui.app.screens.head_to_head_screen import HeadToHeadScreen, HeadToHeadSetup
from racer_tui.app.screens.league_submit import RacerPrompt, RaceSubmitted, submit_race
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.session import keep_race, session_races
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.model_detail import seconds_text
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.widgets.track_label import track_options
from sim.garage.folder import ModelFolder, list_models
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.physics.labels import PHYSICAL
from sim.race.driver import REFERENCE_NAME, reference_driver
from sim.race.head_to_head import Entry
from sim.race.replay import ghost_lap
from sim.race.result import RaceResult
from sim.race.rules import DEFAULT_RULES, HEAD_TO_HEAD_RULES, preset_rules
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track
from sim.tracks.track import Track
from sim.training.drivers import model_driver

REFERENCE = "reference driver"
HEAD_TO_HEAD = "head-to-head"  # the race type whose drivers are chosen in a dialog
RESULT_COLUMNS = (
    "#",
    Col("driver", keep=4, shrink_to=10, collapses=False, cuts_middle=True),
    Col("track", keep=1, shrink_to=8),
    "best lap",
    Col("laps", keep=2),
    Col("off", keep=3),
)
# What tells races apart first, so a narrow terminal still shows it; the rest gives way.
RECORDED_COLUMNS = (
    "when",
    Col("racer", keep=5, shrink_to=8, collapses=False),
    "best lap",
    Col("laps", keep=4),
    # The board, "(physical)" and all: a hand-timed lap must not look like a simulated one.
    Col("track", keep=3, shrink_to=8, collapses=False, keeps_tail=True),
    Col("model", keep=2, shrink_to=8, cuts_middle=True),
    Col("night", keep=1, shrink_to=8),
)
# Below VERY_NARROW there is room for when, who and the best lap only: the board goes too,
# and a lap timed by hand is marked in its place (HAND_TIMED_MARK).
RECORDED_COLUMNS_VERY_NARROW = tuple(
    replace(col, collapses=True) if isinstance(col, Col) and col.label == "track" else col
    for col in RECORDED_COLUMNS
)
RECORDED_LIMIT = 200
WINDOWS = ((240.0, "4:00 (league rules)"), (120.0, "2:00"), (60.0, "1:00"))


@dataclass(frozen=True)
class DriverChoice:
    label: str
    folder: ModelFolder | None  # None: the reference driver
    track: str | None  # the model's own track
    race_type: str | None = None  # the model's own race type (RACE_TYPES' values)


# The race types a race can be run as: (label, rules preset or "" for the time trial).
RACE_TYPE_CHOICES: tuple[tuple[str, str], ...] = (
    ("time trial", ""),
    ("object avoidance, 3 boxes", "object-avoidance"),
    ("head-to-bot, 3 bots", "head-to-bot"),
    ("head-to-head, 2-6 models", HEAD_TO_HEAD),
)
_PRESET_OF_TYPE = {"OBJECT_AVOIDANCE": "object-avoidance", "HEAD_TO_BOT": "head-to-bot"}


@dataclass
class DriversLoaded(Message):
    drivers: list[DriverChoice]
    generation: int  # a cancelled, slower read must not win


def head_to_head_entries(picks: list[DriverChoice], track: Track) -> list[Entry]:
    """The chosen drivers as a head-to-head race's cars (policies load now: in the race
    view's worker)."""
    return [
        Entry(
            pick.label,
            model_driver(pick.folder) if pick.folder is not None else reference_driver(track),
        )
        for pick in picks
    ]


def trained_drivers() -> list[DriverChoice]:
    """The reference driver, then every model that has a policy to drive with."""
    drivers = [DriverChoice(REFERENCE, None, None)]
    for folder in list_models():
        if folder.has_policy():
            try:
                params = folder.training_params()
            except ValueError:
                continue  # a damaged folder: the garage shows what is wrong with it
            race = _PRESET_OF_TYPE.get(params.race_type.strip().upper(), "")
            drivers.append(DriverChoice(folder.name, folder, params.world_name, race))
    return drivers


@dataclass
class RecordedRacesLoaded(Message):
    races: list[RecordedRace]
    generation: int


# Below NARROW columns the setup column narrows (to NARROW_SETUP, below VERY_NARROW to
# VERY_NARROW_SETUP) and dates lose their year: at 80 the recorded races then keep their
# board ("reinv… (physical)"), so a hand-timed lap never looks like a simulated one.
NARROW = 100
NARROW_SETUP = 29
VERY_NARROW = 80
VERY_NARROW_SETUP = 24
# Pane titles, and the shorter ones that fit below VERY_NARROW.
DRIVERS_TITLE = ("Driver (trained models)", "Driver (trained)")
RECORDED_TITLE = ("Recorded races in the league, newest first", "Recorded races, newest first")
# Below VERY_NARROW the track column, and "(physical)" with it, is gone: a hand-timed lap is
# marked so it never looks like a simulated one, and the title says what the mark means.
HAND_TIMED_MARK = "*"
RECORDED_TITLE_HAND_TIMED = "Recorded races, newest (* by hand)"


def recorded_row(
    race: RecordedRace, *, short: bool = False, mark_physical: bool = False
) -> list[str | Text]:
    """A recorded race's cells; dim when it has no trace here to replay. `short`: the
    date without its year (a narrow terminal: "05-04 19:00", never a cut time).
    `mark_physical`: the track column is gone, so a lap timed by hand carries
    `HAND_TIMED_MARK` after its time (the title says what it means)."""
    when = race.started_at[:16].replace("T", " ")
    best = seconds_text(race.best_lap)
    if mark_physical and race.physics == PHYSICAL:
        best = f"{best}{HAND_TIMED_MARK}"
    cells: list[str | Text] = [
        when[5:] if short else when,
        Text(race.display_name),
        best,
        str(race.valid_laps),
        Text(race.track_label),
        Text(race.model_name),
        Text(race.night_name or "-"),
    ]
    if race.has_trace:
        return cells
    return [Text(cell.plain if isinstance(cell, Text) else cell, style="dim") for cell in cells]


def replay_setup(replay: RaceReplay) -> RaceSetup:
    result = replay.result
    return RaceSetup(
        track=replay.track,
        rules=result.rules,
        racer=result.racer,
        replay=result,
        title=f"Replay: {result.racer} on {replay.track.name}",
    )


def replay_recorded_race(screen: Screen[Any], race_id: str, db_path: Path | None) -> None:
    """Open the race view replaying a race recorded in the league, from its stored trace.

    The race and its track are read in a thread worker of `screen`: a race without a trace
    here, or on a track this machine does not have, fails there with one sentence, which a
    RacerScreen shows as a notification."""
    app = screen.app

    def load() -> None:
        with open_league(db_path) as league:
            setup = replay_setup(race_replay(league, race_id))

        def show() -> None:  # on the app's thread: screens are made and pushed there
            app.push_screen(RaceScreen(setup))

        app.call_from_thread(show)

    screen.run_worker(load, thread=True, group="race-replay", exclusive=True, exit_on_error=False)


class RacesScreen(RacerScreen[None]):
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "start_race", "Start race", tooltip="The chosen driver on the chosen track"),
        Binding(
            "p",
            "replay",
            "Replay",
            tooltip="Replay the highlighted race (this session's or the league's)",
        ),
        Binding(
            "u",
            "submit_race",
            "Submit to league",
            tooltip="Record the highlighted race of this session in the league, under your name",
        ),
        Binding("ctrl+r", "reload", "Reload", tooltip="Find newly trained models and races"),
    ]
    DEFAULT_CSS = """
    RacesScreen #race-history > Label { width: 100%; text-wrap: nowrap; text-overflow: ellipsis; }
    """

    def __init__(self, *, db_path: Path | None = None) -> None:
        """`db_path` None is the league in the data folder."""
        super().__init__()
        self.db_path = db_path
        self.drivers: list[DriverChoice] = []
        self.recorded: list[RecordedRace] = []
        self.submitted: dict[str, str] = {}  # result id -> the racer it was submitted as
        self.submitting: set[str] = set()
        self.racer_prompt = RacerPrompt(self, db_path)
        self._generation = 0

    def compose(self) -> ComposeResult:
        yield SectionHeader("races")
        with Horizontal(id="races-body"):
            with Vertical(id="race-setup"):
                yield Label(DRIVERS_TITLE[0], classes="field-label", id="drivers-title")
                yield FittedTable(id="drivers", cursor_type="row", show_header=False)
                yield Label("Track", classes="field-label")
                yield Select(
                    self._track_options(), value=DEFAULT_TRACK, allow_blank=False, id="race-track"
                )
                yield Label("Race type", classes="field-label")
                yield Select(
                    [(label, preset) for label, preset in RACE_TYPE_CHOICES],
                    value="",
                    allow_blank=False,
                    id="race-type",
                )
                yield Label("Window", classes="field-label")
                yield Select(
                    [(label, seconds) for seconds, label in WINDOWS],
                    value=WINDOWS[0][0],
                    allow_blank=False,
                    id="race-window",
                )
                yield Button("Start race (s)", id="start-race", variant="primary")
            with Vertical(id="race-history"):
                yield Label("Races this session, best first", classes="field-label")
                yield FittedTable(id="race-results", cursor_type="row", zebra_stripes=True)
                yield Label(RECORDED_TITLE[0], classes="field-label", id="recorded-title")
                yield FittedTable(id="recorded-races", cursor_type="row", zebra_stripes=True)
                yield Static(
                    "p or Enter replays the highlighted race (dim: no trace here); u submits "
                    "it to the league (✓: submitted). New races race the track's best lap so "
                    "far as a ghost (g).",
                    id="races-hint",
                )
        yield RacerFooter()

    def on_mount(self) -> None:
        fill_table(self.query_one("#race-results", DataTable), RESULT_COLUMNS, [])
        fill_table(self.query_one("#recorded-races", DataTable), RECORDED_COLUMNS, [])

    @property
    def results(self) -> list[RaceResult]:
        """This app run's races, best first (the Garage's too: see racer_tui.app.session)."""
        return rank(session_races(self.app))

    def on_screen_resume(self) -> None:
        """Each time the section is shown (the first time too): models may have been
        trained, and races run from the Garage, since."""
        self.action_reload()
        self._show_results(select=self.highlighted_result)  # back from a dialog: keep it

    def action_reload(self) -> None:
        self._generation += 1
        self._load_drivers(self._generation)
        self._load_recorded(self._generation)

    @work(thread=True, exclusive=True, group="race-drivers", exit_on_error=False)
    def _load_drivers(self, generation: int) -> None:
        self.post_message(DriversLoaded(trained_drivers(), generation))

    @work(thread=True, exclusive=True, group="recorded-races", exit_on_error=False)
    def _load_recorded(self, generation: int) -> None:
        with open_league(self.db_path) as league:
            races = recent_races(league, RECORDED_LIMIT)
        self.post_message(RecordedRacesLoaded(races, generation))

    def on_recorded_races_loaded(self, message: RecordedRacesLoaded) -> None:
        if message.generation != self._generation:
            return
        table = self.query_one("#recorded-races", DataTable)
        chosen = self.highlighted_recorded
        self.recorded = message.races
        self._fill_recorded()
        ids = [race.race_id for race in message.races]
        if chosen is not None and chosen.race_id in ids:
            table.move_cursor(row=ids.index(chosen.race_id))

    def _fill_recorded(self) -> None:
        short = self.has_class("-narrow")
        very_narrow = self.has_class("-very-narrow")
        rows = [
            recorded_row(race, short=short, mark_physical=very_narrow) for race in self.recorded
        ]
        columns = RECORDED_COLUMNS_VERY_NARROW if very_narrow else RECORDED_COLUMNS
        fill_table(self.query_one("#recorded-races", DataTable), columns, rows)
        marked = very_narrow and any(race.physics == PHYSICAL for race in self.recorded)
        title = RECORDED_TITLE_HAND_TIMED if marked else RECORDED_TITLE[very_narrow]
        self.query_one("#recorded-title", Label).update(title)

    def on_resize(self) -> None:
        width = self.size.width
        narrow, very_narrow = width < NARROW, width < VERY_NARROW
        if (narrow, very_narrow) != (self.has_class("-narrow"), self.has_class("-very-narrow")):
            # The history needs the room: the setup narrows (its own style, over the app
            # stylesheet's width) and dates lose their year.
            setup = VERY_NARROW_SETUP if very_narrow else NARROW_SETUP if narrow else None
            self.query_one("#race-setup").styles.width = setup
            self.set_class(narrow, "-narrow")
            self.set_class(very_narrow, "-very-narrow")
            self.query_one("#drivers-title", Label).update(DRIVERS_TITLE[very_narrow])
            self._fill_recorded()  # and its title

    @property
    def highlighted_recorded(self) -> RecordedRace | None:
        table = self.query_one("#recorded-races", DataTable)
        if 0 <= table.cursor_row < len(self.recorded):
            return self.recorded[table.cursor_row]
        return None

    def on_drivers_loaded(self, message: DriversLoaded) -> None:
        if message.generation != self._generation:
            return
        table = self.query_one("#drivers", DataTable)
        chosen = self.chosen_driver
        self.drivers = message.drivers
        rows = [
            [Text(driver.label, style="italic" if driver.folder is None else "")]
            for driver in message.drivers
        ]
        column = Col("driver", keep=0, shrink_to=12, collapses=False, cuts_middle=True)
        fill_table(table, [column], rows)
        labels = [driver.label for driver in self.drivers]
        if chosen is not None and chosen.label in labels:
            table.move_cursor(row=labels.index(chosen.label))

    @property
    def chosen_driver(self) -> DriverChoice | None:
        table = self.query_one("#drivers", DataTable)
        if 0 <= table.cursor_row < len(self.drivers):
            return self.drivers[table.cursor_row]
        return None

    @on(DataTable.RowHighlighted, "#drivers")
    def _driver_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if not 0 <= event.cursor_row < len(self.drivers):
            return
        driver = self.drivers[event.cursor_row]
        track = driver.track
        select = self.query_one("#race-track", Select)
        if track is not None and track in {value for _, value in self._track_options()}:
            select.value = track
        if driver.race_type is not None:  # a model races the race type it trained for
            self.query_one("#race-type", Select).value = driver.race_type

    def _track_options(self) -> list[tuple[Text, str]]:
        return track_options()

    @on(DataTable.RowSelected, "#drivers")
    @on(Button.Pressed, "#start-race")
    def action_start_race(self) -> None:
        driver = self.chosen_driver
        if driver is None:
            self.notify("Choose a driver first.", severity="warning")
            return
        track = resolve_track(str(self.query_one("#race-track", Select).value))
        window = self.query_one("#race-window", Select).value
        preset = str(self.query_one("#race-type", Select).value)
        if preset == HEAD_TO_HEAD:
            self._ask_head_to_head(track, float(str(window)))
            return
        base = preset_rules(preset) if preset else DEFAULT_RULES
        rules = replace(base, window_seconds=float(str(window)))
        same_track = [r for r in self.results if r.track_hash == track.content_hash]
        # The session's leader on this track, or else the league's best lap there: the
        # first race of a track has a ghost too when the league has a lap on it.
        leader = same_track[0] if same_track else self._league_leader(track)
        setup = RaceSetup(
            track=track,
            rules=rules,
            racer=driver.label,
            driver=partial(model_driver, driver.folder) if driver.folder is not None else None,
            ghost=ghost_lap(leader) if leader is not None else None,
            leader_seconds=leader.score if leader is not None else None,
            title=f"{driver.label} on {track.name}",
        )
        self.app.push_screen(RaceScreen(setup), self._race_finished)

    def _ask_head_to_head(self, track: Track, window: float) -> None:
        """Who races, then the race: the highlighted driver is chosen already."""
        drivers = list(self.drivers)
        table = self.query_one("#drivers", DataTable)
        first = table.cursor_row if 0 <= table.cursor_row < len(drivers) else None

        def chosen(request: HeadToHeadRequest | None) -> None:
            if request is None:
                return
            picks = [drivers[k] for k in request.drivers]
            rules = replace(HEAD_TO_HEAD_RULES, window_seconds=window, lap_count=request.laps)
            setup = HeadToHeadSetup(
                track=track,
                rules=rules,
                names=tuple(pick.label for pick in picks),
                entries=partial(head_to_head_entries, picks, track),
            )
            self.app.push_screen(HeadToHeadScreen(setup))

        labels = [driver.label for driver in drivers]
        self.app.push_screen(HeadToHeadDialog(labels, first, track.name), chosen)

    def _league_leader(self, track: Track) -> RaceResult | None:
        """The league's recorded race with the best lap on `track` (of this physics, with
        its trace), or None; a league that cannot be read gives no ghost, never an error."""
        try:
            with open_league(self.db_path) as league:
                race_id = best_lap_race(league, track.content_hash, CURRENT_PHYSICS)
                return race_result(league, race_id) if race_id is not None else None
        except (OSError, sqlite3.Error, LeagueError, ValueError):
            return None

    def _race_finished(self, result: RaceResult | None) -> None:
        keep_race(self.app, result)
        if result is not None:
            self._show_results(select=result)

    def _show_results(self, select: RaceResult | None = None) -> None:
        table = self.query_one("#race-results", DataTable)
        results = self.results
        rows: list[list[str | Text]] = []
        for place, result in enumerate(results, start=1):
            best = result.best_lap
            driver = Text(result.racer)
            if result.result_id in self.submitted:
                driver = Text.assemble(("✓ ", "bold green"), driver)
            rows.append(
                [
                    str(place),
                    driver,
                    Text(result.track_name),
                    seconds_text(best.time_seconds) if best is not None else "-",
                    str(result.valid_laps),
                    str(result.total_offtracks),
                ]
            )
        fill_table(table, RESULT_COLUMNS, rows)
        if select is not None:
            table.move_cursor(row=results.index(select))

    @property
    def highlighted_result(self) -> RaceResult | None:
        table = self.query_one("#race-results", DataTable)
        results = self.results
        return results[table.cursor_row] if 0 <= table.cursor_row < len(results) else None

    def action_submit_race(self) -> None:
        """Submit the highlighted race of this session to the league (asks who is racing
        the first time)."""
        if self.query_one("#recorded-races", DataTable).has_focus:
            self.notify(
                "The recorded races are in the league already; u submits a race from "
                '"Races this session".',
                severity="warning",
            )
            return
        result = self.highlighted_result
        if result is None:
            self.notify(
                "There is no race to submit yet; choose a trained model and press s to race it.",
                severity="warning",
            )
            return
        if result.model_name == REFERENCE_NAME:
            self.notify(
                "The reference driver's races are not league entries; race a trained model "
                "and submit that.",
                severity="warning",
            )
            return
        if result.result_id in self.submitted:
            self.notify(
                f"This race is already in the league as {self.submitted[result.result_id]}'s; "
                "a race is submitted once.",
                severity="warning",
                markup=False,
            )
            return
        if result.result_id in self.submitting:
            return  # the first press is still being recorded
        self.racer_prompt.then(
            f"{result.racer}'s race on {result.track_name} goes to the league.",
            partial(self._submit, result),
        )

    def _submit(self, result: RaceResult, racer: str) -> None:
        self.submitting.add(result.result_id)
        self._record_submission(result, racer)

    @work(thread=True, group="race-submit", exit_on_error=False)
    def _record_submission(self, result: RaceResult, racer: str) -> None:
        try:
            self.post_message(submit_race(result, racer, self.db_path))
        finally:
            self.submitting.discard(result.result_id)

    def on_race_submitted(self, message: RaceSubmitted) -> None:
        self.submitted[message.result_id] = message.racer
        chosen = self.highlighted_result
        self._show_results(select=chosen)
        self.notify(message.sentence, title="League", timeout=12, markup=False)
        self.action_reload()  # the race is in the recorded list now

    def action_replay(self) -> None:
        """Replay from the focused table; the league's when it has focus, or when no race
        has run this session."""
        recorded = self.query_one("#recorded-races", DataTable)
        if recorded.has_focus or not session_races(self.app):
            self.replay_recorded()
            return
        result = self.highlighted_result
        if result is None:
            self.notify("There is no race to replay yet; press s to start one.", severity="warning")
            return
        track = resolve_track(result.track_name)
        setup = RaceSetup(
            track=track,
            rules=result.rules,
            racer=result.racer,
            replay=result,
            title=f"Replay: {result.racer} on {track.name}",
        )
        self.app.push_screen(RaceScreen(setup))

    @on(DataTable.RowSelected, "#race-results")
    def _result_selected(self) -> None:
        self.action_replay()

    @on(DataTable.RowSelected, "#recorded-races")
    def replay_recorded(self) -> None:
        race = self.highlighted_recorded
        if race is None:
            self.notify(
                "There is no recorded race to replay yet: submit a race from this session "
                "(u), or run a league night (5, then n).",
                severity="warning",
            )
            return
        replay_recorded_race(self, race.race_id, self.db_path)

"""League nights for the host: create a season, open a night (in a season or not), enter
racers, draw the order, run each heat live in the race view, watch the standings after every
heat, close the night and see the season's standings.

The league library does the work (league.nights, league.races, league.seasons); this screen
calls it in thread workers, each with its own database connection, and shows what changed.
A heat's race runs in RaceScreen under the night's frozen rules and the heat's seed; the
result it returns is recorded with `record_race` into the night.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from datetime import date
from functools import partial
from pathlib import Path
from typing import ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.widgets import Button, DataTable, Input, Label, Select, Static
from textual.worker import Worker, WorkerState

from league.bracket_nights import (
    MatchCars,
    bracket_rules,
    draw_night_bracket,
    left_out_note,
    next_match,
    record_match,
    still_qualifying,
)
from league.bracket_records import read_bracket
from league.brackets import MIN_ENTRANTS
from league.errors import LeagueError
from league.live_heat import LiveHeatWriter, live_heat_path
from league.local_racer import HOST_NAME, local_racer_name
from league.night_report import night_export
from league.night_state import NightState, read_night
from league.night_verification import uncounted_heats
from league.nights import (
    Entrant,
    Heat,
    Night,
    add_entrant,
    close_night,
    delete_night,
    draw_heats,
    entrant_note,
    entrants,
    find_night_track,
    heats,
    list_nights,
    move_heat,
    new_night,
    night_date,
    pending_heats,
    replay_heats,
    standings,
    withdraw_entrant,
)
from league.opening import open_league
from league.racers import check_name
from league.races import race_result, record_race
from league.report import SCORE_TITLES, seconds
from league.seasons import (
    DEFAULT_POINTS,
    list_seasons,
    new_season,
    parse_points,
)
from league.store import League, default_db_path
from league.timekeeper.car import PHYSICAL, car_name, is_physical
from league.timekeeper.journal import HeatJournal, journal_path
from racer_tui.app.jobs import sentence
from racer_tui.app.league_watch import LEAGUE_POLL_SECONDS, LeagueWatch
from racer_tui.app.screens.base import RacerScreen, error_message
from racer_tui.app.screens.dialogs import (
    FormDialog,
    InputDialog,
    NameInput,
    NameOrPathSuggester,
    PathSuggester,
    ask,
    show_problem,
)
from racer_tui.app.screens.export_path import EXPORT_FORMATS, check_export_path, export_folder
from racer_tui.app.screens.head_to_head_screen import HeadToHeadScreen
from racer_tui.app.screens.match_timekeeper import MatchTimekeeperScreen, MatchTimekeeperSetup
from racer_tui.app.screens.night_bracket import (
    BracketRequest,
    DrawBracketDialog,
    MatchReady,
    match_setup,
)
from racer_tui.app.screens.night_projector import NightProjectorScreen
from racer_tui.app.screens.race_screen import RaceScreen, RaceSetup
from racer_tui.app.screens.timekeeper import TimekeeperScreen, TimekeeperSetup
from racer_tui.app.web_pages import WebPages, WebPagesError
from racer_tui.app.widgets.bracket_view import bracket_view
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.section_header import SectionHeader
from racer_tui.app.widgets.table_fill import Col, FittedTable, fill_table
from racer_tui.app.widgets.track_label import track_options
from sim.foundation.atomic import write_text_atomic
from sim.foundation.plural import counted
from sim.garage.folder import list_models
from sim.physics.labels import CURRENT as CURRENT_PHYSICS
from sim.physics.labels import PHYSICAL as HAND_TIMED  # a result's physics, not a car spec
from sim.physics.objects.settings import RaceType
from sim.race.driver import REFERENCE_NAME
from sim.race.head_to_head import HeadToHeadResult
from sim.race.replay import ghost_lap
from sim.race.result import RaceResult
from sim.race.rules import (
    DEFAULT_RULES,
    RULE_PRESETS,
    RaceRules,
    RankingMethod,
    RulesError,
    load_rules,
    preset_rules,
    rules_from_mapping,
)
from sim.tracks.catalog import DEFAULT_TRACK, resolve_track
from sim.tracks.track import Track
from sim.training.drivers import DriversByHash, resolve_driver

# In the narrow panes the optional columns (keep 1 and 2) give way before a name loses its end.
NAME = Col("", keep=3, shrink_to=10, collapses=False)
# A night's name loses its middle, never its end: "Walk night 2" and "Walk night 3" cut at
# the end looked like one night ("Walk nigh…" twice at 60x20).
NIGHT_COLUMNS = (
    # Cut no narrower than every night still reads unlike the others ("Brack…ight" was
    # both Bracket Night and Bracket Fight at 60x20, in the host walk).
    replace(NAME, label="night", cuts_middle=True, stays_distinct=True),
    Col("track", keep=1, shrink_to=8),
    Col("state"),
)
# The car says who is physical and which car: it loses the middle of "physical: car1"
# ("phys…car1"), never its column (cut at the end, two physical cars looked alike).
HEAT_COLUMNS = (
    "#",
    replace(NAME, label="racer", shrink_to=8),
    Col("car", keep=2, shrink_to=9, collapses=False, cuts_middle=True),
    Col("result", keep=1, shrink_to=11, collapses=False),  # "best 10.569" is never cut
)
MIXED_STANDINGS_NOTE = (
    "physical and simulated laps ranked together here; the League keeps physical laps "
    "on a board of their own"
)
RACER = replace(NAME, label="racer")
# league.ranking's order past the score, for standings whose figures read alike.
TIE_NOTE = (
    "Equal scores are placed by fewer off-tracks in the scoring laps, then more laps, then "
    "the earlier result."
)


# --- dialogs ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class NightRequest:
    track: str
    name: str | None
    rules: RaceRules  # read and checked in the dialog, frozen in the night when it opens
    season_id: str | None
    held_on: date | None = None  # None: today


# The ranking choices of the open-night dialog; None keeps the rules' own.
RANKINGS: list[tuple[str, RankingMethod]] = [
    ("ranked by best lap", RankingMethod.BEST_LAP),
    ("ranked by best average of consecutive laps", RankingMethod.BEST_AVERAGE),
    ("ranked by total time of the first laps", RankingMethod.TOTAL_TIME),
]


def read_night_rules(path: str) -> tuple[RaceRules | None, str | None]:
    """The rules in the file at `path` (empty: the league's), or what is wrong with it."""
    if not path:
        return DEFAULT_RULES, None
    file = Path(path).expanduser()
    if not file.is_file():
        return None, f"There is no rules file {path}; check the path or leave it empty."
    try:
        return load_rules(file), None
    except (RulesError, OSError) as error:
        text = str(error)
        return None, text[:1].upper() + text[1:]


class NewNightDialog(FormDialog[NightRequest]):
    """Track, optional name, optional rules file and laps (a lap-count race), ranking and
    season. Enter moves to the next field; the button or Ctrl+S opens the night. The rules
    are read here, so a bad file is said under the fields with nothing typed lost; they
    are frozen when the night opens and shown (read-only) on the night afterwards."""

    # Six rows of fields, three rows each, do not fit 24 with the title and buttons.
    COMPACT_FIELDS_BELOW_ROWS = 34

    DEFAULT_CSS = """
    NewNightDialog #night-name-row { height: auto; }
    NewNightDialog #night-name { width: 1fr; }
    NewNightDialog #night-date { width: 17; }
    NewNightDialog #night-rules-row { height: auto; }
    NewNightDialog #night-rules { width: 1fr; }
    NewNightDialog #night-laps { width: 26; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("ctrl+s", "open_night", "Open night", priority=True),
    ]

    def __init__(self, seasons: list[tuple[str, str]], season_id: str | None = None) -> None:
        """`seasons` as (name, id); `season_id` is chosen to start with (None: no season)."""
        super().__init__()
        self._seasons = seasons
        known = {value for _, value in seasons}
        self._season_id = season_id if season_id in known else None

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label("Open a league night", classes="dialog-title")
            yield Label("Track", classes="field-label")
            yield Select(track_options(), value=DEFAULT_TRACK, allow_blank=False, id="night-track")
            with Horizontal(id="night-name-row"):
                # Names keep what was typed, invisible characters too, for the check to refuse.
                yield NameInput(placeholder="night name (empty: track and date)", id="night-name")
                # Anything typed stays as typed: a date the host mistypes is said back to
                # them as they wrote it, never silently trimmed.
                yield Input(placeholder="date: today", max_length=10, id="night-date")
            yield Select(
                [(f"{name} rules: {what}", name) for name, what, _ in RULE_PRESETS],
                value=RULE_PRESETS[0][0],
                allow_blank=False,
                id="night-preset",
            )
            with Horizontal(id="night-rules-row"):
                yield Input(
                    placeholder="or a rules YAML file",
                    suggester=PathSuggester(),
                    id="night-rules",
                )
                # A lap-count race: each heat ends after this many laps (the rules' window
                # still its time limit).
                yield Input(placeholder="laps (empty: rules')", restrict=r"[0-9]*", id="night-laps")
            yield Select(RANKINGS, prompt="ranked as the rules say", id="night-ranking")
            yield Select(
                self._seasons,
                prompt="no season",
                value=self._season_id if self._season_id is not None else Select.NULL,
                id="night-season",
            )
            yield Static(
                Text(
                    "The rules are frozen when the night opens; for real cars timed by "
                    "hand, choose the physical rules. Enter moves to the next field; "
                    "Ctrl+S opens the night."
                ),
                classes="dialog-body",
            )
            yield from self.form_buttons("Open night")

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#night-name", Input))

    @on(Input.Submitted)
    def _next_field(self) -> None:
        self.focus_next()

    def action_open_night(self) -> None:
        self._confirm()

    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        path = self.query_one("#night-rules", Input).value.strip()
        preset = str(self.query_one("#night-preset", Select).value)
        rules, problem = read_night_rules(path) if path else (preset_rules(preset), None)
        if rules is None:
            show_problem(self.query_one("#problem", Static), problem or "")
            self.query_one("#night-rules", Input).focus()
            return
        held_on = None
        typed_date = self.query_one("#night-date", Input).value.strip()
        if typed_date:
            try:
                held_on = night_date(typed_date)
            except LeagueError as error:
                text = str(error)
                show_problem(self.query_one("#problem", Static), text[:1].upper() + text[1:])
                self.query_one("#night-date", Input).focus()
                return
        ranking = self.query_one("#night-ranking", Select).value
        laps = self.query_one("#night-laps", Input).value.strip()
        chosen: dict[str, object] = {}
        if isinstance(ranking, RankingMethod):
            chosen["ranking"] = ranking.value
        if laps:
            chosen["lap_count"] = int(laps)
        try:
            rules = rules_from_mapping(chosen, base=rules)
        except RulesError as error:
            text = str(error)
            text = text[:1].upper() + text[1:]
            if laps and 0 < int(laps) < rules.ranking_laps:  # say what to change here
                text = (
                    f"A race of {laps} laps cannot be ranked over {rules.ranking_laps} laps: "
                    f"give at least {rules.ranking_laps} laps, or rank by best lap."
                )
            show_problem(self.query_one("#problem", Static), text)
            self.query_one("#night-laps", Input).focus()
            return
        season = self.query_one("#night-season", Select).value
        name = self.query_one("#night-name", Input).value.strip() or None
        if name is not None:
            try:  # said here, with the name still there to change (the host walk)
                name = check_name(name, "night name")
            except LeagueError as error:
                show_problem(self.query_one("#problem", Static), sentence(str(error)))
                self.query_one("#night-name", Input).focus()
                return
        self.dismiss(
            NightRequest(
                track=str(self.query_one("#night-track", Select).value),
                name=name,
                rules=rules,
                season_id=None if season is Select.NULL else str(season),
                held_on=held_on,
            )
        )


def car_cell(entrant: Entrant) -> Text:
    """The car in the heats table, its kind first for a physical one ("physical: blue
    car"): a narrow table cuts the end, and who is physical must stay readable."""
    if is_physical(entrant.model):
        name = car_name(entrant.model)
        return Text(name if name == "physical car" else f"physical: {name}")
    return Text(entrant.car)


@dataclass(frozen=True)
class EntrantRequest:
    racer: str
    model: str


class AddEntrantDialog(FormDialog[str]):
    """A racer and what they race: `reference`, a garage model, a bundle file or a physical
    car."""

    # At 24 rows the form fills the screen to its last row, and the note under the car
    # (training, or a physical car under simulator rules) pushed the buttons below it.
    COMPACT_FIELDS_BELOW_ROWS = 30

    def __init__(
        self,
        models: list[str],
        add: Callable[[EntrantRequest], str],
        *,
        training: frozenset[str] = frozenset(),
        physical_rules: bool = True,
    ) -> None:
        """`add` enters the racer (blocking, in this dialog's worker) and says so, or raises
        what the league refuses: the dialog stays open with what was typed and says why.
        `training`: the models training now (entered with a warning); `physical_rules`:
        the night races under the physical preset (else a physical car gets a note)."""
        super().__init__()
        self._models = models
        self._add = add
        self._training = training
        self._physical_rules = physical_rules

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label("Add an entrant", classes="dialog-title")
            yield Static(
                "The racer, and the car: `reference` (the reference driver), a garage model, "
                "a .racer-bundle file, or `physical` for a real car timed by hand "
                "(`physical:NAME` names it); → completes.",
                classes="dialog-body",
            )
            yield NameInput(placeholder="racer name", id="entrant-racer")
            yield Input(
                placeholder="reference, a model, a bundle path or physical",
                suggester=NameOrPathSuggester([REFERENCE_NAME, PHYSICAL, *self._models]),
                id="entrant-model",
            )
            note = Static("", id="entrant-note", classes="dialog-body")
            note.display = False
            yield note
            yield from self.form_buttons("Add")

    @on(Input.Changed, "#entrant-model")
    def _note(self, event: Input.Changed) -> None:
        """What a host should know about this car before entering it (it is still allowed)."""
        note = entrant_note(
            event.value.strip(), training=self._training, physical_rules=self._physical_rules
        )
        shown = self.query_one("#entrant-note", Static)
        shown.update(Text(note, style="yellow"))
        shown.display = bool(note)  # no empty rows pushing the buttons down when none

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#entrant-racer", Input))

    @on(Input.Submitted, "#entrant-racer")
    def _next_field(self) -> None:
        self.query_one("#entrant-model", Input).focus()

    @on(Input.Submitted, "#entrant-model")
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        racer = self.query_one("#entrant-racer", Input).value.strip()
        model = self.query_one("#entrant-model", Input).value.strip()
        if not racer or not model:
            show_problem(
                self.query_one("#problem", Static),
                "Give the racer's name and the car (reference, a model, a bundle or physical).",
            )
            return
        self._enter(EntrantRequest(racer, model))

    @work(thread=True, exclusive=True, group="entrant-add", exit_on_error=False)
    def _enter(self, request: EntrantRequest) -> None:
        try:
            said = self._add(request)
        except Exception as error:  # the league's refusal, said where the host typed
            self.app.call_from_thread(
                show_problem, self.query_one("#problem", Static), error_message(error)
            )
            return
        self.app.call_from_thread(self.dismiss, said)


@dataclass(frozen=True)
class SeasonRequest:
    name: str
    points: tuple[int, ...]


def season_problem(name: str, points: str, taken: list[str]) -> str | None:
    """What is wrong with a new season's name or points table, in one sentence, or None.
    The league checks again when it creates the season."""
    if not name.strip():
        return "Give the season a name, for example Spring 2025."
    try:
        clean = check_name(name, "season name")
        if points.strip():
            parse_points(points)
    except LeagueError as error:
        text = str(error)
        return text[:1].upper() + text[1:]
    if clean.casefold() in {other.casefold() for other in taken}:
        return f"There is already a season called {clean!r}; pick another name."
    return None


class NewSeasonDialog(FormDialog[SeasonRequest]):
    """A season's name and its points table (empty: the league's default table)."""

    def __init__(self, taken: list[str]) -> None:
        super().__init__()
        self._taken = taken

    def compose(self) -> ComposeResult:
        default = ",".join(map(str, DEFAULT_POINTS))
        with Vertical(classes="dialog"):
            yield Label("Create a season", classes="dialog-title")
            yield Static(
                "The nights you open in this season add up to its standings when they close. "
                "Points go to places 1, 2, 3, ... in the order given.",
                classes="dialog-body",
            )
            yield NameInput(placeholder="season name, e.g. Spring 2025", id="season-name")
            yield Input(placeholder=f"points by place (empty: {default})", id="season-points")
            yield from self.form_buttons("Create season")

    def on_mount(self) -> None:
        self.focus_first(self.query_one("#season-name", Input))

    @on(Input.Submitted, "#season-name")
    def _next_field(self) -> None:
        self.query_one("#season-points", Input).focus()

    @on(Input.Submitted, "#season-points")
    @on(Button.Pressed, "#confirm")
    def _confirm(self) -> None:
        name = self.query_one("#season-name", Input).value
        points = self.query_one("#season-points", Input).value
        problem = season_problem(name, points, self._taken)
        if problem is not None:
            show_problem(self.query_one("#problem", Static), problem)
            # Back to the field the sentence is about (the host walk cleared a good name).
            named = season_problem(name, "", self._taken) is not None
            self.query_one("#season-name" if named else "#season-points", Input).focus()
            return
        table = parse_points(points) if points.strip() else DEFAULT_POINTS
        self.dismiss(SeasonRequest(name.strip(), table))


# --- messages from the workers --------------------------------------------------------------


@dataclass
class NightsLoaded(Message):
    nights: list[Night]
    select: str | None


@dataclass
class NightLoaded(Message):
    state: NightState


@dataclass
class NightChanged(Message):
    """Something was added to a night: say so, then read it again."""

    night_id: str
    note: str
    focus_entrant: str | None = None  # keep this entrant's row highlighted


@dataclass
class SeasonsLoaded(Message):
    seasons: list[tuple[str, str]]  # (name, id)
    purpose: str = "night"  # "night": for the new night dialog; "season": a new season


@dataclass
class SeasonCreated(Message):
    season_id: str
    name: str


@dataclass
class HeatReady(Message):
    night: Night
    heat: Heat
    setup: RaceSetup | TimekeeperSetup


def heat_setup(
    league: League, night: Night, heat: Heat, track: Track, league_file: Path | None = None
) -> RaceSetup | TimekeeperSetup:
    """The race view's setup for a heat: the night's rules, the heat's seed, and the
    night's leader so far as the ghost and the gap; a physical car's heat is the
    timekeeper's. Either tells the night's projector where the heat is."""
    entrant = heat.entrant
    number = heat.position
    car = entrant.car  # a bundle's or folder's file name, not its path: the venue sees it
    live = LiveHeatWriter(
        live_heat_path(league_file or default_db_path(), night.id),
        night_id=night.id,
        heat_id=heat.id,
        heat_number=number,
        racer=entrant.display_name,
        car=car,
    )
    if is_physical(entrant.model):
        return TimekeeperSetup(
            track=track,
            rules=night.rules,
            racer=entrant.racer,
            car=car_name(entrant.model),  # the result's car: its name, as boards key it
            title=f"Heat {number}: {entrant.display_name}, {car}",
            live=live,
            journal=HeatJournal(journal_path(league_file or default_db_path(), heat.id), heat.id),
        )
    # The leader on this heat's own board: a hand-timed lap is never a simulated heat's
    # ghost or gap (the host walk saw "gap +4.029" to a physical car's time).
    leader = next(
        (
            s.entry
            for s in standings(league, night)
            if s.entry.score is not None and s.entry.physics == CURRENT_PHYSICS
        ),
        None,
    )
    ghost = ghost_lap(race_result(league, leader.record_id)) if leader is not None else None
    return RaceSetup(
        track=track,
        rules=night.rules,
        racer=heat.entrant.racer,
        driver=partial(resolve_driver, heat.entrant.model, track),
        seed=heat.seed,
        ghost=ghost,
        leader_seconds=leader.score if leader is not None else None,
        leader_name=leader.display_name if leader is not None else "",
        title=f"Heat {number}: {heat.entrant.display_name} ({entrant.car})",
        live=live,
    )


# A dialog-preparing worker that ended without posting its dialog.
STOPPED_WITHOUT_RESULT = (WorkerState.ERROR, WorkerState.CANCELLED)


def did_not_race(what: str) -> str:
    """What a heat or match whose car could not be driven needs: r alone fails again."""
    return (
        f"{what} did not race: a car could not be driven (the race view said why). Fix the "
        "car, or withdraw its entrant (w), then r runs it."
    )


class NightsScreen(RacerScreen[None]):
    """The nights on the left; the highlighted night's rules, heats and standings."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("o", "open_night", "Open night", tooltip="A new night: track, rules, season"),
        Binding("a", "add_entrant", "Add entrant", tooltip="A racer and their car"),
        Binding("d", "draw", "Draw", tooltip="Draw the order of the heats still to race"),
        Binding("r", "run_heat", "Run heat", tooltip="Race the next heat live"),
        Binding("c", "close_night", "Close night", tooltip="Final standings and season points"),
        # Once a season, so out of the footer (the help and the palette list it): the
        # projector's key is worth the room at 80 columns.
        Binding(
            "s", "new_season", "New season", tooltip="Its nights add up to standings", show=False
        ),
        Binding("p", "projector", "Projector", tooltip="The night on the venue's big screen"),
        Binding(
            "k",
            "draw_bracket",
            "Draw bracket",
            tooltip="Once the heats are raced: a knock-out seeded by the night's standings",
            show=False,
        ),
        Binding(
            "x",
            "export",
            "Export night",
            tooltip="Standings with points as CSV or Markdown, or the whole night as JSON",
            show=False,
        ),
        Binding(
            "w",
            "withdraw",
            "Withdraw entrant",
            tooltip="Take the highlighted entrant out before their heat",
            show=False,
        ),
        Binding(
            "b",
            "web_pages",
            "Web pages",
            tooltip="The leaderboard, the night and its live heat in any browser (b again stops)",
            show=False,
        ),
        Binding(
            "left_square_bracket",
            "move_heat(-1)",
            "Heat earlier",
            tooltip="Move the highlighted waiting heat up the running order",
            show=False,
        ),
        Binding(
            "right_square_bracket",
            "move_heat(1)",
            "Heat later",
            tooltip="Move the highlighted waiting heat down the running order",
            show=False,
        ),
        Binding(
            "delete",
            "delete_night",
            "Delete night",
            tooltip="Delete a night no heat has raced on",
            show=False,
        ),
        Binding("escape", "leave", "Back"),
        # The sections' digits work from a section's own screen only (a stray one must not
        # leave a dialog or a heat): here, where a host tried them, they say so.
        Binding("1,2,3,4,5", "sections_hint", show=False),
    ]
    # At 60 columns the long labels leave out c and p, the keys a host needs by the end.
    FOOTER_SHORT_LABELS: ClassVar[dict[str, str]] = {
        "open_night": "Open",
        "add_entrant": "Add",
        "close_night": "Close",
    }
    AUTO_FOCUS = "#nights"
    DEFAULT_CSS = """
    NightsScreen #nights-body { height: 1fr; }
    NightsScreen #nights-list { width: 30; padding: 0 1; }
    NightsScreen.-narrow #nights-list { width: 22; }
    NightsScreen #standings-note { height: auto; color: $warning; }
    NightsScreen #web-note { height: auto; color: $success; }
    NightsScreen #nights { height: 1fr; }
    NightsScreen #night-view { width: 1fr; padding: 0 1; }
    NightsScreen #night-rules { height: auto; }
    NightsScreen #heats { height: 1fr; min-height: 4; }
    NightsScreen #standings { height: 1fr; min-height: 4; }
    /* No night: only the sentence saying how to open one (not a deleted night's tables). */
    NightsScreen.-no-night #night-view .field-label, NightsScreen.-no-night #heats,
    NightsScreen.-no-night #standings, NightsScreen.-no-night #standings-note,
    NightsScreen.-no-night #bracket, NightsScreen.-no-night #season { display: none; }
    NightsScreen #season { height: 1fr; min-height: 4; }
    NightsScreen .-hidden { display: none; }
    NightsScreen.-short #heats, NightsScreen.-short #standings, NightsScreen.-short #season {
        height: auto;
    }
    """

    def __init__(self, *, db_path: Path | None = None) -> None:
        super().__init__()
        self.db_path = db_path
        self.nights: list[Night] = []
        self._listed = False  # the nights list has landed
        self._dialog_coming = False  # a worker prepares the dialog the last key asked for
        self.state: NightState | None = None
        # The night the pane shows or is loading: the list's cursor decides it, never the
        # order in which loads come back.
        self.showing: str | None = None
        self.new_season_id: str | None = None  # created here: new nights start in it
        self.heat_rows: list[tuple[Heat | None, Entrant]] = []  # the heats table's rows
        self._follow: str | None = None  # an entrant whose row the cursor follows (a move)
        self._recorded_heats: set[str] = set()  # heats this screen has sent to the league
        self.web_pages = WebPages()  # `racer-tui serve`, when the host starts it here (b)
        self.league_watch = LeagueWatch(db_path)  # writes made elsewhere (the command line)

    def compose(self) -> ComposeResult:
        yield SectionHeader("league", "league nights")
        with Horizontal(id="nights-body"):
            with Vertical(id="nights-list"):
                yield Label("League nights", classes="field-label")
                yield FittedTable(id="nights", cursor_type="row", zebra_stripes=True)
                yield Static("", id="web-note", classes="-hidden")
            # Scrolls where the night's rules, heats and standings do not all fit (60x20):
            # Tab to the standings brings them into view.
            with VerticalScroll(id="night-view", can_focus=False):
                yield Static("", id="night-rules")
                # Short: the pane is 36 columns wide at 60x20.
                yield Label("Heats, in running order", classes="field-label")
                yield FittedTable(id="heats", cursor_type="row", zebra_stripes=True)
                yield Label("", id="bracket-title", classes="field-label -hidden")
                yield Static("", id="bracket", classes="-hidden")
                yield Label("Standings", id="standings-title", classes="field-label")
                yield Static("", id="standings-note", classes="-hidden")
                yield FittedTable(id="standings", cursor_type="row", zebra_stripes=True)
                # A closed night of a season: where it left the season, under its own.
                yield Label("", id="season-title", classes="field-label -hidden")
                yield FittedTable(id="season", cursor_type="row", classes="-hidden")
        yield RacerFooter()

    def on_mount(self) -> None:
        self.reload()
        self.set_interval(LEAGUE_POLL_SECONDS, self._look_for_changes)

    def on_screen_resume(self) -> None:
        self._look_for_changes()  # back from a heat, a dialog or another section

    def _look_for_changes(self) -> None:
        """Read the league again when another process wrote to it (`racer-tui night ...`,
        a sync): the screen shows what the league holds, not what it held when last read.
        Only while the screen is shown; its return looks at once."""
        if not self.is_current or not self.league_watch.changed():
            return
        if self.heat_rows and self.state is not None:  # the cursor stays on its entrant
            row = self.query_one("#heats", DataTable).cursor_row
            if 0 <= row < len(self.heat_rows):
                self._follow = self.heat_rows[row][1].id
        self.reload()

    def on_resize(self) -> None:
        # Below 80 columns the night's own tables need the room more than the list does.
        self.set_class(self.size.width < 80, "-narrow")
        # Below 24 rows the rules, heats and standings do not all fit: each table is as tall
        # as its rows and the pane scrolls, rather than each table getting a sliver.
        self.set_class(self.size.height < 24, "-short")

    # --- loading -----------------------------------------------------------------------

    def reload(self, select: str | None = None) -> None:
        self.league_watch.reading()
        self._load_nights(select or (self.state.night.id if self.state else None))

    @work(thread=True, exclusive=True, group="nights-list", exit_on_error=False)
    def _load_nights(self, select: str | None) -> None:
        with open_league(self.db_path) as league:
            found = list(reversed(list_nights(league)))  # newest first
        self.post_message(NightsLoaded(found, select))

    def on_nights_loaded(self, message: NightsLoaded) -> None:
        self.nights = message.nights
        self._listed = True
        rows = [
            [Text(n.name), Text(n.track_name), "closed" if n.closed else "open"]
            for n in message.nights
        ]
        table = self.query_one("#nights", DataTable)
        fill_table(table, NIGHT_COLUMNS, rows)
        self.set_class(not self.nights, "-no-night")
        if not self.nights:
            self.state = self.showing = None
            self.query_one("#night-rules", Static).update(
                Text(
                    "No league nights yet. Press o to open one (s first creates a season "
                    "for it to count in).",
                    style="dim",
                )
            )
            return
        ids = [n.id for n in self.nights]
        index = ids.index(message.select) if message.select in ids else 0
        table.move_cursor(row=index)
        self._show_night(ids[index], again=True)

    @on(DataTable.RowHighlighted, "#nights")
    def _night_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self.nights):
            self._show_night(self.nights[event.cursor_row].id)

    def _show_night(self, night_id: str, *, again: bool = False) -> None:
        """Show the night under the cursor (`again`: read it even if it is shown: it
        changed). A list filled afresh highlights its first row before the cursor moves to
        the night chosen, so the last night asked for wins, not the last read."""
        if again or night_id != self.showing:
            self.showing = night_id
            self._load_night(night_id)

    @work(thread=True, exclusive=True, group="night-view", exit_on_error=False)
    def _load_night(self, night_id: str) -> None:
        with open_league(self.db_path) as league:
            state = read_night(league, night_id)
        self.post_message(NightLoaded(state))

    def on_night_loaded(self, message: NightLoaded) -> None:
        if message.state.night.id != self.showing:
            return  # read for a row the cursor has left since
        self.state = state = message.state
        night = state.night
        text = Text()
        text.append(night.name, style="bold")
        held = "" if night.held_on in night.name else f", {night.held_on}"  # said once
        text.append(f"  on {night.track_name}{held}  ")
        text.append("closed" if night.closed else "open", style="dim" if night.closed else "green")
        if state.season_name:
            text.append(f"  season {state.season_name}")
        text.append("\nRules (frozen): ", style="dim")
        rules, described = night.rules, night.rules.describe()
        if rules.race_type is not RaceType.TIME_TRIAL and described.startswith(rules.race_words):
            # Not a time trial: the race type first, where the host's eye lands.
            text.append(rules.race_words, style="bold")
            described = described.removeprefix(rules.race_words)
        text.append(described)
        self.query_one("#night-rules", Static).update(text)
        self._show_heats(state)
        self._show_bracket(state)
        self._show_standings(state)

    def _show_heats(self, state: NightState) -> None:
        rows: list[list[str | Text]] = []
        # What each row is, for the keys that act on the highlighted one.
        self.heat_rows = [*((heat, heat.entrant) for heat in state.heats)]
        self.heat_rows += [(None, entrant) for entrant in state.undrawn]
        next_marked = False
        for number, heat in enumerate(state.heats, start=1):
            if heat.race_id is not None:
                best = state.best_laps.get(heat.race_id)
                result = Text("no lap counted" if best is None else f"best {seconds(best)}")
            elif not next_marked and not state.night.closed:
                result = Text("next (r)", style="bold green")
                next_marked = True
            else:
                result = Text("waiting", style="dim")
            rows.append(
                [str(number), Text(heat.entrant.display_name), car_cell(heat.entrant), result]
            )
        for entrant in state.undrawn:  # listed as they are added, before any draw
            waiting = Text("to draw (d)", style="dim")
            rows.append(["", Text(entrant.display_name), car_cell(entrant), waiting])
        table = self.query_one("#heats", DataTable)
        fill_table(table, HEAT_COLUMNS, rows)
        follow, self._follow = self._follow, None
        ids = [entrant.id for _, entrant in self.heat_rows]
        if follow in ids:
            table.move_cursor(row=ids.index(follow))

    def _show_bracket(self, state: NightState) -> None:
        """The bracket as it stands; before it is drawn, once the heats are all raced on
        an open night, the key that draws it."""
        title = self.query_one("#bracket-title", Label)
        view = self.query_one("#bracket", Static)
        drawn = state.bracket
        qualified = bool(state.heats) and not state.undrawn and all(h.race_id for h in state.heats)
        title.set_class(drawn is None and not (qualified and not state.night.closed), "-hidden")
        view.set_class(drawn is None, "-hidden")
        if drawn is None:
            title.update(Text("Bracket: none yet, k draws it"))  # fits 60 columns
            return
        upcoming = drawn.next_match()
        after = f", next {upcoming.id} (r)" if upcoming and not state.night.closed else ""
        title.update(Text(f"Bracket ({drawn.bracket.format.value} elimination{after})"))
        view.update(bracket_view(drawn, state.names))

    def _show_standings(self, state: NightState) -> None:
        self._show_night_standings(state)
        self._show_season(state)

    def _show_season(self, state: NightState) -> None:
        title = self.query_one("#season-title", Label)
        table = self.query_one("#season", DataTable)
        title.set_class(state.season is None, "-hidden")
        table.set_class(state.season is None, "-hidden")
        if state.season is None:
            return
        title.update(Text(f"Season standings: {state.season_name}"))
        rows: list[list[str | Text]] = [
            [str(s.position), Text(s.display_name), str(s.points), str(s.nights), str(s.wins)]
            for s in state.season
        ]
        fill_table(table, ("#", RACER, "points", Col("nights", keep=2), Col("wins", keep=1)), rows)

    def _show_night_standings(self, state: NightState) -> None:
        table = self.query_one("#standings", DataTable)
        title = self.query_one("#standings-title", Label)
        closed = "final, " if state.night.closed else ""
        title.update(Text(f"Standings ({closed}with points)"))
        kinds = {s.entry.physics for s in state.standings}  # each its own League board
        notes = [sentence(MIXED_STANDINGS_NOTE)] if len(kinds) > 1 else []
        scores = [s.entry.score for s in state.standings if s.entry.score is not None]
        if len(scores) != len(set(scores)):  # equal figures, different places: say why
            notes.append(TIE_NOTE)
        note = self.query_one("#standings-note", Static)
        note.update(Text(" ".join(notes)))
        note.set_class(not notes, "-hidden")
        score_title = SCORE_TITLES[state.night.rules.ranking]
        rows: list[list[str | Text]] = [
            [
                str(s.position) if s.position is not None else "-",
                Text(s.entry.display_name),
                seconds(s.entry.score),
                str(s.entry.valid_laps),
                str(s.entry.offtracks),
                str(s.points),
            ]
            for s in state.standings
        ]
        columns = ("#", RACER, score_title, Col("laps", keep=2), Col("off", keep=1), "points")
        fill_table(table, columns, rows)

    def on_night_changed(self, message: NightChanged) -> None:
        if message.note:
            self.notify(message.note, markup=False)
        self._follow = message.focus_entrant
        self.reload(select=message.night_id)

    # --- actions -----------------------------------------------------------------------

    def _current(self, doing: str) -> Night | None:
        if self.showing is not None and (self.state is None or self.state.night.id != self.showing):
            self.notify(f"The night is still being read; {doing} in a moment.", severity="warning")
            return None
        if self.state is None:
            self.notify(f"Open a night first (o), then {doing}.", severity="warning")
            return None
        if self.state.night.closed:
            self.notify(
                f"{self.state.night.name} is closed; its results are final. Open a new night (o).",
                severity="warning",
                markup=False,
            )
            return None
        return self.state.night

    @property
    def ready_for_keys(self) -> bool:
        """The app holds keys typed before the list has landed, and those typed after `o` or
        `s` until their dialog is open (racer_tui.app.application)."""
        return self._listed and not self._dialog_coming

    def action_open_night(self) -> None:
        self._dialog_coming = True
        self._load_seasons()

    @work(thread=True, exclusive=True, group="nights-dialog", exit_on_error=False)
    def _load_seasons(self, purpose: str = "night") -> None:
        with open_league(self.db_path) as league:
            seasons = [(season.name, season.id) for season in list_seasons(league)]
        self.post_message(SeasonsLoaded(seasons, purpose))

    def on_seasons_loaded(self, message: SeasonsLoaded) -> None:
        self._dialog_coming = False  # the dialog is on top now: keys wait for it to mount
        if message.purpose == "season":
            taken = [name for name, _ in message.seasons]
            self.app.push_screen(NewSeasonDialog(taken), self._season_requested)
            return
        # The season created here, or else the newest: the league's current season, also
        # after a restart (a night opened outside it would lose its points to the season).
        newest = message.seasons[-1][1] if message.seasons else None
        dialog = NewNightDialog(message.seasons, self.new_season_id or newest)
        self.app.push_screen(dialog, self._night_requested)

    def action_new_season(self) -> None:
        self._dialog_coming = True
        self._load_seasons("season")

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        super().on_worker_state_changed(event)
        if event.worker.group == "nights-dialog" and event.state in STOPPED_WITHOUT_RESULT:
            self._dialog_coming = False  # its failure is said; keys go to the screen again

    def _season_requested(self, request: SeasonRequest | None) -> None:
        if request is not None:
            self._create_season(request)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _create_season(self, request: SeasonRequest) -> None:
        with open_league(self.db_path) as league:
            season = new_season(league, request.name, request.points)
        self.post_message(SeasonCreated(season.id, season.name))

    def on_season_created(self, message: SeasonCreated) -> None:
        self.new_season_id = message.season_id
        self.notify(
            f"Created season {message.name}; nights you open now (o) count in it.",
            markup=False,
        )

    def _night_requested(self, request: NightRequest | None) -> None:
        if request is not None:
            self._open_night(request)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _open_night(self, request: NightRequest) -> None:
        track = resolve_track(request.track)
        with open_league(self.db_path) as league:
            night = new_night(
                league,
                track,
                rules=request.rules,
                name=request.name,
                season=request.season_id,
                held_on=request.held_on,
            )
        self.post_message(
            NightChanged(night.id, f"Opened {night.name} on {night.track_name}, {night.held_on}.")
        )

    def action_add_entrant(self) -> None:
        night = self._current("add entrants")
        if night is not None and self.state is not None and self.state.bracket is not None:
            # Said before the dialog, not after it was filled in (the host walk).
            self.notify(
                f"{night.name}'s bracket is drawn, so its entrants are set; open a new night "
                "(o) for more racers.",
                severity="warning",
                markup=False,
            )
            return
        if night is not None:
            folders = [folder for folder in list_models() if folder.has_policy()]
            models = [folder.name for folder in folders]
            training = frozenset(folder.name for folder in folders if folder.is_training())
            physical = night.rules == preset_rules(PHYSICAL)
            dialog = AddEntrantDialog(
                models,
                partial(self._add_entrant, night),
                training=training,
                physical_rules=physical,
            )
            self.app.push_screen(dialog, partial(self._entrant_added, night))

    def _entrant_added(self, night: Night, said: str | None) -> None:
        if said is not None:
            self.post_message(NightChanged(night.id, said))

    def _add_entrant(self, night: Night, request: EntrantRequest) -> str:
        """Enter a racer on the night (blocking: the dialog's worker runs it)."""
        with open_league(self.db_path) as league:
            entrant = add_entrant(league, night, request.racer, request.model)
        return f"Entered {entrant.racer} with {entrant.car}."

    def action_draw(self) -> None:
        night = self._current("draw the heats")
        if night is not None:
            self._draw(night)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _draw(self, night: Night) -> None:
        with open_league(self.db_path) as league:
            raced = {heat.entrant.id for heat in heats(league, night) if heat.race_id}
            if all(entrant.id in raced for entrant in entrants(league, night)):
                # The library's sentence names the CLI command; here the key does it.
                raise LeagueError(
                    f"{night.name} has no entrants waiting to race; add one (a), then draw (d)."
                )
            drawn = draw_heats(league, night)
        waiting = sum(1 for heat in drawn if heat.race_id is None)
        self.post_message(NightChanged(night.id, f"Drew the order of {counted(waiting, 'heat')}."))

    def action_run_heat(self) -> None:
        night = self._current("run its heats")
        if night is not None:
            self._prepare_heat(night)

    @work(thread=True, exclusive=True, group="nights-heat", exit_on_error=False)
    def _prepare_heat(self, night: Night) -> None:
        with open_league(self.db_path) as league:
            waiting = pending_heats(league, night)
            drawn = read_bracket(league, night.id) if not waiting else None
            if drawn is not None:  # the qualifying is over: the bracket's next match
                cars = next_match(league, night)
                if cars is None:
                    raise LeagueError(
                        f"{night.name}'s bracket is decided; close the night (c) to make "
                        "its places final."
                    )
                track = find_night_track(night)
                match = match_setup(drawn, cars, track, self.db_path)
                self.post_message(MatchReady(night, cars, match))
                return
            if not waiting and heats(league, night):
                raise LeagueError(
                    f"{night.name}'s heats are all raced; add entrants (a) and draw (d) for "
                    "more, draw a bracket from its standings (k), or close it (c)."
                )
            if not waiting:
                raise LeagueError(
                    f"{night.name} has no drawn heats waiting; add entrants (a) and draw (d)."
                )
            track = find_night_track(night)
            setup = heat_setup(league, night, waiting[0], track, self.db_path)
        self.post_message(HeatReady(night, waiting[0], setup))

    def on_match_ready(self, message: MatchReady) -> None:
        setup = message.setup
        view = (
            MatchTimekeeperScreen(setup)
            if isinstance(setup, MatchTimekeeperSetup)
            else HeadToHeadScreen(setup)
        )
        self.app.push_screen(view, partial(self._match_finished, message.night, message.cars, view))

    def _match_finished(
        self,
        night: Night,
        cars: MatchCars,
        view: HeadToHeadScreen | MatchTimekeeperScreen,
        result: HeadToHeadResult | None,
    ) -> None:
        if isinstance(view, HeadToHeadScreen) and view.failure:
            self.notify(did_not_race(cars.match.id), severity="warning", markup=False)
            return
        if result is None:
            self.notify(
                f"{cars.match.id} was left before its race finished; press r to race it again.",
                severity="warning",
                markup=False,
            )
            return
        self._record_match(night, cars, result)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _record_match(self, night: Night, cars: MatchCars, result: HeadToHeadResult) -> None:
        with open_league(self.db_path) as league:
            record_match(league, night, cars.match.id, result)
        # Recorded: a physical match has nothing left to resume.
        key = f"{night.id}-{cars.match.id}"
        journal_path(self.db_path or default_db_path(), key).unlink(missing_ok=True)
        winner = result.cars[0].result.racer
        loser = cars.second if winner == cars.first.racer else cars.first
        won = cars.first if loser is cars.second else cars.second
        said = f"Recorded {cars.match.id}: {won.display_name} beat {loser.display_name}."
        self.post_message(NightChanged(night.id, said))

    def action_sections_hint(self) -> None:
        self.notify("Esc goes back to the League; from there 1-5 switch sections.")

    def action_draw_bracket(self) -> None:
        night = self._current("draw its bracket")
        state = self.state
        if night is None or state is None:
            return
        # What the league would refuse, said before the dialog is filled in (the host walk).
        waiting = sum(1 for heat in state.heats if heat.race_id is None) + len(state.undrawn)
        counting = [s for s in state.standings if s.position is not None]
        qualified = sum(1 for s in counting if s.entry.physics != HAND_TIMED)
        physical = len(counting) - qualified
        problem = None
        if state.bracket is not None:
            problem = f"{night.name}'s bracket is drawn already; r races its next match."
        elif waiting:
            problem = sentence(still_qualifying(night, waiting))
        elif max(qualified, physical) < MIN_ENTRANTS:
            problem = (
                f"{night.name} has {counted(qualified, 'racer')} with a counting result in a "
                f"simulated car and {physical} in a physical one; a bracket races one kind, "
                f"and needs {MIN_ENTRANTS}."
            )
        if problem is not None:
            self.notify(problem, severity="warning", markup=False)
            return
        dialog = DrawBracketDialog(qualified, physical)
        self.app.push_screen(dialog, partial(self._bracket_chosen, night))

    def _bracket_chosen(self, night: Night, request: BracketRequest | None) -> None:
        if request is not None:
            self._draw_bracket(night, request)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _draw_bracket(self, night: Night, request: BracketRequest) -> None:
        rules = bracket_rules(night, request.laps, physical=request.physical)
        with open_league(self.db_path) as league:
            drawn = draw_night_bracket(
                league,
                night,
                format=request.format,
                size=request.size,
                rules=rules,
                physical=request.physical,
            )
            note = left_out_note(league, night)
        seeds = counted(len(drawn.bracket.seeds), "racer")
        said = f"Drew the bracket of {seeds}: r races its first match. {note}".rstrip()
        self.post_message(NightChanged(night.id, said))

    def on_heat_ready(self, message: HeatReady) -> None:
        setup, night, heat = message.setup, message.night, message.heat
        screen: RacerScreen[RaceResult | None]
        if isinstance(setup, TimekeeperSetup):
            screen = TimekeeperScreen(setup)
        else:
            # Recorded as its finish is shown: leaving the view records nothing more.
            record = partial(self._record_heat, night, heat)
            screen = RaceScreen(replace(setup, record=record))
        self.app.push_screen(screen, partial(self._heat_finished, night, heat, screen))

    def _heat_finished(
        self,
        night: Night,
        heat: Heat,
        view: RacerScreen[RaceResult | None],
        result: RaceResult | None,
    ) -> None:
        if heat.id in self._recorded_heats:
            return
        if getattr(view, "failure", None):  # r would fail the same way: say what helps
            self.notify(did_not_race(f"Heat {heat.position}"), severity="warning", markup=False)
            return
        if result is None:
            self.notify(
                f"Heat {heat.position} was left before its race finished; press r to run it again.",
                severity="warning",
                markup=False,
            )
            return
        self._record(night, heat, result)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _record(self, night: Night, heat: Heat, result: RaceResult) -> None:
        self._record_heat(night, heat, result)

    def _record_heat(self, night: Night, heat: Heat, result: RaceResult) -> None:
        """Put a heat's result on the night (in a worker thread: this screen's, or the race
        view's as the heat's finish is shown); raises what the league refuses."""
        with open_league(self.db_path) as league:
            record_race(league, result, night.id, heat_id=heat.id)
        # Recorded: a physical car's heat has nothing left to resume.
        journal_path(self.db_path or default_db_path(), heat.id).unlink(missing_ok=True)
        self._recorded_heats.add(heat.id)
        best = result.best_lap
        lap = f"best lap {best.time_seconds:.3f} s" if best is not None else "no valid lap"
        self.post_message(NightChanged(night.id, f"Recorded {heat.entrant.racer}'s heat: {lap}."))

    def action_close_night(self) -> None:
        night = self._current("close it")
        if night is None or self.state is None:
            return
        drawn = self.state.bracket
        upcoming = drawn.next_match() if drawn is not None else None
        if upcoming is not None:  # said before the question, with the key that helps
            self.notify(
                f"{night.name} has bracket matches still to race; r races the next "
                f"({upcoming.id}), and the night closes once the bracket is decided.",
                severity="warning",
                markup=False,
            )
            return
        waiting = sum(1 for heat in self.state.heats if heat.race_id is None)
        extra = (
            f" {counted(waiting, 'heat')} {'has' if waiting == 1 else 'have'} not raced; those "
            "entrants get no result."
            if waiting
            else ""
        )
        if night.rules.verification.requires:
            extra += (
                f" Its rules count {night.rules.verification.words}, so its simulated heats "
                "are raced again here first."
            )
        ask(
            self.app,
            f"Close {night.name}?",
            (
                "Closing makes the standings final and adds the points to the season; "
                if night.season_id is not None
                else "Closing makes the standings final; "
            )
            + f"no more entrants, draws or heats.{extra}",
            partial(self._close_confirmed, night, bool(waiting)),
            confirm_label="Close night",
        )

    def _close_confirmed(self, night: Night, force: bool, yes: bool | None) -> None:
        if yes:
            self._close(night, force)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _close(self, night: Night, force: bool) -> None:
        # Under a verification rule the night's simulated heats are raced again here first,
        # as `racer-tui night close` does: a heat that differs is withdrawn, and one the
        # rule does not count is said, each in a sentence.
        drivers = DriversByHash() if night.rules.verification.requires else None
        with open_league(self.db_path) as league:
            closer = local_racer_name(league) or HOST_NAME
            withdrawn = [] if drivers is None else replay_heats(league, night, drivers)
            try:
                close_night(league, night, closer, force=force)
            except LeagueError:
                # Heats drawn elsewhere since the night was shown, or withdrawn just now:
                # show them, so the next c asks about them (the error says so).
                self.post_message(NightChanged(night.id, " ".join(withdrawn)))
                raise
            left_out = (
                [] if drivers is None else uncounted_heats(league, night, drivers.models_here())
            )
        said = " ".join([f"Closed {night.name}; the standings are final.", *withdrawn, *left_out])
        self.post_message(NightChanged(night.id, said))

    def _highlighted_entrant(self, doing: str) -> tuple[Heat | None, Entrant] | None:
        """The row under the heats table's cursor; the first press only moves there."""
        table = self.query_one("#heats", DataTable)
        if not self.heat_rows:
            self.notify(f"There is nobody to {doing}: add an entrant (a).", severity="warning")
            return None
        if self.focused is not table:
            table.focus()
            self.notify(f"Highlight the entrant (↑ ↓), then press the key again to {doing}.")
            return None
        return self.heat_rows[min(table.cursor_row, len(self.heat_rows) - 1)]

    def action_withdraw(self) -> None:
        night = self._current("withdraw an entrant")
        row = self._highlighted_entrant("withdraw them") if night is not None else None
        if night is None or row is None:
            return
        heat, entrant = row
        if heat is not None and heat.race_id is not None:
            self.notify(
                f"{entrant.display_name} has raced; their result stays.",
                severity="warning",
                markup=False,
            )
            return
        ask(
            self.app,
            f"Withdraw {entrant.display_name}?",
            f"{entrant.display_name} ({entrant.car}) leaves the running order; they can be "
            "entered again (a).",
            partial(self._withdraw_confirmed, night, entrant),
            confirm_label="Withdraw",
        )

    def _withdraw_confirmed(self, night: Night, entrant: Entrant, yes: bool | None) -> None:
        if yes:
            self._withdraw(night, entrant)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _withdraw(self, night: Night, entrant: Entrant) -> None:
        with open_league(self.db_path) as league:
            withdraw_entrant(league, night, entrant.id, local_racer_name(league) or HOST_NAME)
        self.post_message(NightChanged(night.id, f"Withdrew {entrant.display_name}."))

    def action_move_heat(self, offset: int) -> None:
        night = self._current("change the running order")
        row = self._highlighted_entrant("move their heat") if night is not None else None
        if night is None or row is None:
            return
        heat = row[0]
        if heat is None or heat.race_id is not None:
            self.notify(
                "Only a drawn heat still to race moves; draw first (d).", severity="warning"
            )
            return
        self._move(night, heat, offset)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _move(self, night: Night, heat: Heat, offset: int) -> None:
        with open_league(self.db_path) as league:
            move_heat(league, night, heat.id, offset)
        self.post_message(NightChanged(night.id, "", focus_entrant=heat.entrant.id))

    def action_delete_night(self) -> None:
        night = self._current("delete it")
        if night is None or self.state is None:
            return
        if any(heat.race_id is not None for heat in self.state.heats):
            self.notify(
                f"{night.name} has raced heats, so it cannot be deleted; close it instead (c): "
                "its results stay in the league.",
                severity="warning",
                markup=False,
            )
            return
        ask(
            self.app,
            f"Delete {night.name}?",
            "No heat has raced on it. Its entrants and draw go with it.",
            partial(self._delete_confirmed, night),
            confirm_label="Delete night",
        )

    def _delete_confirmed(self, night: Night, yes: bool | None) -> None:
        if yes:
            self._delete(night)

    @work(thread=True, group="nights-change", exit_on_error=False)
    def _delete(self, night: Night) -> None:
        with open_league(self.db_path) as league:
            delete_night(league, night, local_racer_name(league) or HOST_NAME)
        self.post_message(NightChanged("", f"Deleted {night.name}."))

    def action_export(self) -> None:
        """Any night, open or closed (an open one says its standings are so far)."""
        if self.state is None or self.state.night.id != self.showing:
            self.notify("Open a night first (o), then export it.", severity="warning")
            return
        night = self.state.night
        stem = "".join(c if c.isalnum() or c in "-_" else "-" for c in night.name).strip("-")
        dialog = InputDialog(
            f"Export {night.name}",
            "The night's standings with points. The file name's ending chooses the format: "
            ".csv or .md (Markdown) for the standings, .json for the whole night (rules, "
            "entrants, heats and standings).",
            value=str(export_folder() / f"{stem or 'night'}.csv"),
            confirm_label="Export",
            check=check_export_path,
            paths=True,
        )
        self.app.push_screen(dialog, partial(self._export_to, self.state))

    def _export_to(self, state: NightState, path: str | None) -> None:
        if path is not None:
            target = Path(path).expanduser()
            self._export(state, target, EXPORT_FORMATS[target.suffix.lower()])

    @work(thread=True, group="nights-export", exit_on_error=False)
    def _export(self, state: NightState, path: Path, kind: str) -> None:
        with open_league(self.db_path) as league:
            entrants_now = entrants(league, state.night)
        text = night_export(
            state.night, entrants_now, state.heats, state.standings, kind, bracket=state.bracket
        )
        write_text_atomic(path, text)
        self.post_message(NightChanged(state.night.id, f"Wrote {state.night.name} to {path}."))

    def action_projector(self) -> None:
        """Any night, open or closed: a closed one shows its final standings."""
        if self.showing is None:
            self.notify(
                "Open a night first (o), then show it on the projector.", severity="warning"
            )
            return
        self.app.push_screen(NightProjectorScreen(self.showing, db_path=self.db_path))

    def action_web_pages(self) -> None:
        """Start the league's web pages, or stop them if they run."""
        if self.web_pages.starting:
            return  # its address comes in a moment
        if self.web_pages.running:
            self._stop_web_pages()
            return
        self._start_web_pages()

    @work(thread=True, exclusive=True, group="web-pages", exit_on_error=False)
    def _start_web_pages(self) -> None:
        try:
            said = self.web_pages.start(self.db_path)
        except WebPagesError as error:
            self.app.call_from_thread(self.notify, str(error), severity="error")
            return
        # Nothing to show if the screen was left while it started: it was stopped then.
        if said and self.is_attached:
            self.app.call_from_thread(self._show_web_pages, said)

    @work(thread=True, exclusive=True, group="web-pages", exit_on_error=False)
    def _stop_web_pages(self) -> None:
        self.web_pages.stop()
        self.app.call_from_thread(self._show_web_pages, "")

    def _show_web_pages(self, said: str) -> None:
        note = self.query_one("#web-note", Static)
        pages = self.web_pages
        address = pages.address if said else ""
        # Two short lines: the list is 20 columns wide below 80, and an address cut in
        # two is no use to the host reading it out.
        shown = address.removeprefix("http://").removesuffix("/")
        note.update(Text(f"Web pages at\n{shown}" if address else ""))
        note.set_class(not address, "-hidden")
        if address:
            self.notify(
                f"Web pages at {address} ({pages.who}): the leaderboard, /night, /live and "
                "/overlay for a stream. b stops them.",
                timeout=10,
            )
        else:
            self.notify("The web pages are stopped.")

    def on_unmount(self) -> None:
        self.web_pages.stop()

    def action_leave(self) -> None:
        self.dismiss(None)

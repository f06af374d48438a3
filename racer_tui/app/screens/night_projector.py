"""A league night on the venue's big screen: the night and its track, the heat running
now, and the night's standings with points, the newest result highlighted for a while.

The standings come from the league database, read again every few seconds (heats end
in this racer-tui or in another one beside it); the heat in progress comes from the
small file its screen writes (`league.live_heat`), read twice a second. Nothing here
needs a key: a host opens it, on the venue's screen, and leaves it. A kiosk
(`racer_tui.app.screens.kiosk`): Esc does nothing, q asks and then leaves, and no other
screen opens from it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from rich import box
from rich.console import Group
from rich.table import Table
from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Digits, Label, Static

from league.errors import LeagueError
from league.live_heat import LiveHeat, live_heat_path, read_live_heat
from league.live_match import LiveMatch, live_match_path, read_live_match
from league.night_state import NightState, read_night
from league.nights import find_night_track
from league.opening import open_league
from league.report import SCORE_TITLES
from league.store import default_db_path
from racer_tui.app.screens.head_to_head_screen import CAR_GLYPH, car_colour
from racer_tui.app.screens.kiosk import LEAVE_HINT, KioskScreen, kiosk_bindings
from racer_tui.app.screens.race_screen import countdown_text
from racer_tui.app.screens.timekeeper import lap_clock_text
from racer_tui.app.widgets.bracket_view import bracket_view
from racer_tui.app.widgets.race_map import RaceMap, RacingCar
from racer_tui.text.clocks import clock_text, elapsed_text
from racer_tui.text.head_to_head import incident_sentence
from sim.foundation.plural import counted
from sim.physics.labels import PHYSICAL
from sim.physics.objects.settings import RaceType
from sim.race.head_to_head import Incident

POLL_SECONDS = 2.0  # the standings, from the database
LIVE_SECONDS = 0.5  # the heat in progress, from its file
HIGHLIGHT_SECONDS = 12.0  # how long a new result stands out
SUFFIXES = {1: "st", 2: "nd", 3: "rd"}


def ordinal(place: int) -> str:
    """1st, 2nd, 3rd, 4th ... 11th, 12th, 13th ... 21st, 22nd."""
    teens = place % 100 in (11, 12, 13)
    return f"{place}{'th' if teens else SUFFIXES.get(place % 10, 'th')}"


@dataclass
class NightGone(Message):
    reason: str


# What the last line says: the view updates itself while the night runs; once it is
# closed its standings are final. Short enough for 60 columns.
OPEN_HINT = f"{LEAVE_HINT} · updates itself as heats run"
CLOSED_HINT = f"{LEAVE_HINT} · the standings are final"


@dataclass
class NightRead(Message):
    state: NightState


NARROW = 70  # below this many columns the gap goes: the names need the room


def places_line(state: NightState) -> Text:
    """The night's places and points in as few lines as they take, where a table has no
    room: "Places: 1 ana 25 · 2 eve 18 · …"."""
    text = Text("Places: ", style="bold")
    for index, standing in enumerate(state.standings):
        if index:
            text.append(" · ", style="dim")
        place = str(standing.position) if standing.position is not None else "-"
        text.append(f"{place} ")
        text.append(standing.entry.display_name, style="bold")  # plain text, never markup
        text.append(f" {standing.points}")
    return text


def standings_table(
    state: NightState,
    highlight: str | None,
    spaced: bool,
    narrow: bool = False,
    rows: int | None = None,
) -> Table:
    """The night's standings in big, spaced rows: one rank per racer (a racer without a
    counting lap is unplaced, '-'), the gap to the leader (not when `narrow`), and the
    points; at most `rows` rows, the last saying how many more there are."""
    table = Table(box=box.SIMPLE_HEAD, expand=True, padding=(0, 1), show_edge=False)
    table.add_column("#", justify="right", style="bold", width=3)
    # The car takes a little more: "blue (physical)" was cut beside a half-empty racer.
    table.add_column("racer", ratio=3, no_wrap=True, overflow="ellipsis")
    table.add_column("car", ratio=4, no_wrap=True, overflow="ellipsis")
    table.add_column(SCORE_TITLES[state.night.rules.ranking], justify="right", width=9)
    if not narrow:
        table.add_column("gap", justify="right", width=8)
    table.add_column("laps", justify="right", width=4)
    table.add_column("pts", justify="right", width=4)
    leader = state.standings[0].entry.score if state.standings else None
    # Once a bracket has placed the night, its champion's qualifying lap is no yardstick:
    # a gap to it went negative ("+-1.610") for a quicker qualifier the bracket ranks below.
    if state.bracket is not None and state.bracket.final_order() is not None:
        leader = None
    # A night of physical cars only needs no "(physical)" on every row: the mark is for a
    # night that mixes them with simulated ones (and it cut the car's name at 80 columns).
    mixed = len({s.entry.physics == PHYSICAL for s in state.standings}) > 1
    shown = state.standings
    if rows is not None and len(shown) > rows:
        shown = shown[: max(rows - 1, 0)]
    for index, standing in enumerate(shown):
        entry = standing.entry
        score = entry.score
        gap = (
            f"+{score - leader:.3f}"
            if score is not None and leader is not None and index and score >= leader
            else ""
        )
        car = entry.model
        if mixed and entry.physics == PHYSICAL and PHYSICAL not in car.casefold():
            car += f" ({PHYSICAL})"
        style = "on grey15" if index % 2 else ""
        if highlight is not None and entry.racer == highlight:
            style = "bold black on yellow"
        cells = [
            Text(str(standing.position) if standing.position is not None else "-"),
            Text(entry.display_name, style="bold"),  # plain text, never markup
            Text(car),
            Text(clock_text(score) if score is not None else "-", style="bold"),
            *([] if narrow else [Text(gap)]),
            Text(str(entry.valid_laps)),
            Text(str(standing.points), style="bold"),
        ]
        table.add_row(*cells, style=style)
        if spaced:
            table.add_row()  # readable from the back of the room
    more = len(state.standings) - len(shown)
    if more:
        table.add_row("", Text(f"and {more} more", style="dim"))
    return table


class NightProjectorScreen(KioskScreen):
    """Full-screen view of one league night for the venue; `db_path` None is the default
    league."""

    BINDINGS: ClassVar[list[BindingType]] = kiosk_bindings(
        Binding("ctrl+r", "refresh_now", "Refresh", show=False),
    )
    what = "night projector"
    DEFAULT_CSS = """
    NightProjectorScreen { background: $background; }
    NightProjectorScreen #np-title {
        height: auto; max-height: 2; padding: 0 2; text-style: bold; color: $accent;
    }
    NightProjectorScreen #np-now { height: 5; padding: 0 2; }
    /* A cell between the heat's lines and the clock: a match's gap ran into its digits. */
    NightProjectorScreen #np-heat { width: 1fr; height: 5; padding: 1 1 0 0; }
    NightProjectorScreen #np-clock-box { width: auto; height: 5; }
    NightProjectorScreen #np-clock-label { width: 100%; text-align: right; color: $text-muted; }
    NightProjectorScreen #np-clock { width: auto; }
    NightProjectorScreen #np-news { height: 1; padding: 0 2; }
    NightProjectorScreen #np-standings { height: 1fr; padding: 0 2; max-width: 120; }
    NightProjectorScreen #np-map { height: 1fr; padding: 0 2; display: none; }
    NightProjectorScreen.-match-on-air #np-map { display: block; }
    NightProjectorScreen.-match-on-air #np-standings { display: none; }
    NightProjectorScreen #np-hint { height: 1; color: $text-muted; padding: 0 2; }
    """

    def __init__(self, night_id: str, *, db_path: Path | None = None) -> None:
        super().__init__()
        self.night_id = night_id
        self.db_path = db_path
        self.clock: Callable[[], float] = time.time  # a test may drive its own
        self.state: NightState | None = None
        self.live: LiveHeat | None = None
        self.match: LiveMatch | None = None  # a bracket match racing now
        self._no_track_here = False  # the night's track is not on this machine: no map
        self.reads = 0
        self.news: Text | None = None
        self.highlight: str | None = None  # the racer of the newest result
        self._highlight_until = 0.0
        self._seen_races: set[str] | None = None  # None: nothing read yet, nothing is new
        self.gone: str | None = None  # why the night cannot be read (deleted since)
        self._live_path = live_heat_path(db_path or default_db_path(), night_id)
        self._match_path = live_match_path(db_path or default_db_path(), night_id)

    def compose(self) -> ComposeResult:
        yield Static(Text("League night"), id="np-title")
        with Horizontal(id="np-now"):
            yield Static("", id="np-heat")
            with Vertical(id="np-clock-box"):
                yield Label("", id="np-clock-label")
                yield Digits("-:--", id="np-clock")
        yield Static("", id="np-news")
        yield Static("", id="np-standings")
        yield RaceMap(id="np-map")  # a bracket match's cars, while it is raced
        yield Static(OPEN_HINT, id="np-hint")

    def on_mount(self) -> None:
        self.action_refresh_now()
        self.set_interval(POLL_SECONDS, self.action_refresh_now)
        self.set_interval(LIVE_SECONDS, self._read_live)

    def on_resize(self) -> None:
        self._draw_standings()  # spaced rows only where they fit

    def action_refresh_now(self) -> None:
        self._read_night()

    # --- reading ---------------------------------------------------------------------------

    @work(thread=True, exclusive=True, group="night-projector", exit_on_error=False)
    def _read_night(self) -> None:
        try:
            with open_league(self.db_path) as league:
                state = read_night(league, self.night_id)
        except LeagueError:  # deleted since: said on the screen, not every 2 s
            self.post_message(
                NightGone("the night is no longer in the league (deleted, here or elsewhere).")
            )
            return
        self.post_message(NightRead(state))

    def on_night_gone(self, message: NightGone) -> None:
        self.gone = message.reason
        self.state = None
        self.query_one("#np-standings", Static).update("")
        self.query_one("#np-news", Static).update("")
        self._draw_now()

    def _read_live(self) -> None:
        live = read_live_heat(self._live_path, self.night_id, self.clock())
        ended = self.live is not None and (live is None or live.heat_id != self.live.heat_id)
        finished = live is not None and live.state == "over"
        if ended or (finished and (self.live is None or self.live.state != "over")):
            self.action_refresh_now()  # its result is in the database now, or soon
        self.live = live
        match = read_live_match(self._match_path, self.night_id, self.clock())
        match_over = self.match is not None and (
            match is None or match.match_id != self.match.match_id or match.state == "over"
        )
        if match_over:
            self.action_refresh_now()  # the bracket advances once the match is recorded
        self.match = match
        if self.highlight is not None and self.clock() >= self._highlight_until:
            self.highlight = None
            self.news = None
            self._draw_standings()
        self._draw_now()

    def on_night_read(self, message: NightRead) -> None:
        self.reads += 1
        self.gone = None
        state = self.state = message.state
        races = {heat.race_id: heat for heat in state.heats if heat.race_id is not None}
        new = sorted(set(races) - self._seen_races) if self._seen_races is not None else []
        self._seen_races = set(races)
        if new:
            self._announce(state, races[new[-1]].entrant.racer, new[-1])
        night = state.night
        title = Text(f"{night.name} · {night.track_name} · ")
        if night.rules.race_type is not RaceType.TIME_TRIAL:
            title.append(night.rules.race_words, style="bold")  # what the cars race among
            title.append(" · ")
        if night.rules.lap_count is not None:
            title.append(f"{night.rules.lap_count}-lap race · ")
        title.append(f"ranked by {SCORE_TITLES[night.rules.ranking]}")
        if night.closed:
            title.append(" · final standings")
        self.query_one("#np-title", Static).update(title)
        self.query_one("#np-hint", Static).update(CLOSED_HINT if night.closed else OPEN_HINT)
        self._draw_standings()
        self._draw_now()

    def _announce(self, state: NightState, racer: str, race_id: str) -> None:
        """Highlight the newest result: its racer's row, and one line saying what it was."""
        standing = next((s for s in state.standings if s.entry.racer == racer), None)
        name = standing.entry.display_name if standing is not None else racer
        best = state.best_laps.get(race_id)
        news = Text("New result: ", style="bold black on yellow")
        news.append(f"{name}, ", style="bold")  # a name is plain text, never markup
        news.append(f"best lap {clock_text(best)}" if best is not None else "no lap counted")
        if standing is not None and standing.position is not None:
            news.append(f", {ordinal(standing.position)} tonight")
        self.news = news
        self.highlight = racer
        self._highlight_until = self.clock() + HIGHLIGHT_SECONDS

    # --- drawing ---------------------------------------------------------------------------

    def _draw_standings(self) -> None:
        state = self.state
        if state is None:
            return
        self.query_one("#np-news", Static).update(self.news or "")
        panel = self.query_one("#np-standings", Static)
        if not state.standings:
            panel.update(Text("No results yet: the standings fill in as heats end.", style="dim"))
            return
        room = panel.size.height
        narrow = 0 < panel.size.width < NARROW
        if state.bracket is not None:  # a bracket night: the bracket first, as it advances
            drawn = bracket_view(state.bracket, state.names)
            # The standings take the rows the bracket leaves (at 60x20 a closed bracket
            # night showed the table's heading and none of its rows): its title, its
            # rule and a blank line take three.
            width = panel.size.width or self.size.width
            lines = len(
                self.app.console.render_lines(drawn, self.app.console.options.update_width(width))
            )
            rows = None if room == 0 else room - lines - 3
            if rows is not None and rows < 3:  # no room for a table: the places in a line
                panel.update(Group(drawn, places_line(state)))
                return
            table = standings_table(state, self.highlight, False, narrow, rows)
            panel.update(Group(drawn, Text(""), table))
            return
        spaced = room == 0 or 2 * len(state.standings) + 2 <= room
        panel.update(standings_table(state, self.highlight, spaced, narrow))

    def _draw_now(self) -> None:
        state, live = self.state, self.live
        heat = self.query_one("#np-heat", Static)
        label = self.query_one("#np-clock-label", Label)
        digits = self.query_one("#np-clock", Digits)
        if state is None:
            if self.gone is not None:
                text = Text("This night cannot be shown: ", style="bold red")
                text.append(f"{self.gone} q leaves.")
                heat.update(text)
            else:
                heat.update(Text("Reading the night…", style="dim"))
            return
        self._draw_match(state)
        if self.match is not None:
            match = self.match
            heat.update(match_on_air(match))
            label.update("Race clock")
            value = elapsed_text(match.clock)
        elif live is not None:
            heat.update(self._heat_on_air(state, live))
            label.update("Time left" if live.state != "over" else "Best lap")
            value = countdown_text(live.time_left)
            if live.state == "over":
                value = clock_text(live.best_lap) if live.best_lap is not None else "-:--"
        else:
            heat.update(self._between_heats(state))
            leader = state.standings[0].entry if state.standings else None
            label.update("Leader" if leader is not None and leader.score is not None else "")
            value = clock_text(leader.score) if leader and leader.score is not None else "-:--"
        if digits.value != value:
            digits.update(value)

    def _draw_match(self, state: NightState) -> None:
        """The match's cars on the track, in their race view colours, in the standings'
        place while it is raced; the bracket and standings again once it is over."""
        match = self.match
        racing = match is not None and match.state == "running"
        racing = racing and self._match_map(state) is not None
        self.set_class(racing, "-match-on-air")
        if not racing or match is None:
            return
        cars = tuple(
            RacingCar(car.at[0], car.at[1], car.heading, car_colour(k), bool(car.held_for))
            for k, car in enumerate(match.cars)
            if car.at is not None
        )
        self.query_one("#np-map", RaceMap).show(None, cars=cars)

    def _match_map(self, state: NightState) -> RaceMap | None:
        """The map, on the night's track (None when this machine does not have it)."""
        drawn = self.query_one("#np-map", RaceMap)
        if drawn.track is None and not self._no_track_here:
            try:
                drawn.set_track(find_night_track(state.night))
            except LeagueError:  # the match is still said in words, above
                self._no_track_here = True
        return None if drawn.track is None else drawn

    def _heat_on_air(self, state: NightState, live: LiveHeat) -> Text:
        text = Text()
        word = {"ready": "On the line", "running": "Racing now", "paused": "Paused"}
        total = len(state.heats)
        text.append(f"{word.get(live.state, 'Just finished')}: ", style="bold green")
        text.append(f"heat {live.heat_number}" + (f" of {total}" if total else ""))
        text.append("\n")
        text.append(live.racer, style="bold")  # plain text, never markup
        text.append(f"  {live.car}\n", style="dim")
        if live.state != "over":
            text.append(f"{state.night.rules.lap_of(live.lap)}  ", style="bold")
            text.append(lap_clock_text(live.lap_time))
            limit = "" if live.limit is None else f"/{live.limit}"
            over = live.limit is not None and live.offtracks > live.limit
            text.append(f"   off {live.offtracks}{limit}", style="red" if over else "")
        text.append("   best ")
        text.append(clock_text(live.best_lap) if live.best_lap is not None else "-", style="bold")
        return text

    def _between_heats(self, state: NightState) -> Text:
        text = Text()
        raced = sum(1 for heat in state.heats if heat.race_id is not None)
        waiting = [heat for heat in state.heats if heat.race_id is None]
        if state.night.closed:
            text.append("The night is over.", style="bold")
            text.append(f"\n{counted(raced, 'heat')} raced · final standings and points below")
            return text
        upcoming = state.bracket.next_match() if state.bracket is not None else None
        if state.bracket is not None and upcoming is not None:
            a, b = state.bracket.sides(upcoming)
            text.append("Next up: ", style="bold green")
            text.append(f"bracket match {upcoming.id}\n")
            text.append(state.names.get(a or "", "?"), style="bold")
            text.append("  v  ", style="dim")
            text.append(state.names.get(b or "", "?"), style="bold")
            return text
        if state.bracket is not None:
            champion = state.bracket.bracket.champion(state.bracket.winners)
            text.append("The bracket is decided", style="bold")
            text.append(f"\nChampion: {state.names.get(champion or '', '?')}")
            return text
        if waiting:
            after = waiting[0]
            text.append("Next up: ", style="bold green")
            text.append(f"heat {raced + 1} of {len(state.heats)}\n")
            text.append(after.entrant.display_name, style="bold")
            text.append(f"  {after.entrant.car}", style="dim")
            return text
        if state.undrawn:
            text.append("Entrants are coming in", style="bold")
            text.append(f"\n{len(state.undrawn)} entered · the running order is drawn next")
            return text
        text.append(f"{counted(raced, 'heat')} raced" if raced else "No heats yet", style="bold")
        return text


def match_on_air(match: LiveMatch) -> Text:
    """A bracket match as it is raced: its round, then each car in the running order in its
    race view colour, with its laps, its gap to the leader and the penalty it is serving,
    then the newest crash or overtake."""
    text = Text()
    racing = match.state == "running"
    text.append("Racing now: " if racing else "Just finished: ", style="bold green")
    text.append(f"{match.title} ({match.match_id})\n")
    grid = {id(car): k for k, car in enumerate(match.cars)}
    for car in match.running_order():
        text.append(f"{car.place} ", style="bold")
        text.append(f"{CAR_GLYPH} ", style=car_colour(grid[id(car)]))
        text.append(car.racer, style="bold")  # plain text, never markup
        text.append(f"  {car.car}", style="dim")
        laps = f"{car.laps}" + (f"/{match.lap_count}" if match.lap_count is not None else "")
        text.append(f"  laps {laps}")
        if car.place > 1 and car.gap is not None:
            text.append(f"  +{car.gap:.2f} s")
        if car.held_for:
            text.append(f"  {car.held_for}", style="red")
        if not racing and car.place == 1:
            text.append("  won", style="bold green")
        text.append("\n")
    if match.incidents:
        newest = match.incidents[-1]
        names = {k: car.racer for k, car in enumerate(match.cars)}
        sentence = incident_sentence(
            Incident(newest.clock, newest.kind, newest.car, newest.other), names
        )
        text.append(f"{elapsed_text(newest.clock)} {sentence}", style="yellow")
    text.rstrip()
    return text

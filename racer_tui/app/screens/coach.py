"""The Coach view: one lap against the limit lap, sector by sector (`sim.coach`).

Opened from the Garage (the model's latest evaluation, its fastest lap) and from the race
view once a race or replay has finished (the race's fastest lap). The limit lap may take a
second or two to work out the first time on a track, so the coaching is made in a thread
worker and the view says so meanwhile. On the left the track, with the limit lap's line and
the car's lap coloured by the time each sector loses; on the right the sectors ranked by
time lost; below them the chosen sector's sentence and the speed round the lap against the
target speed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import DataTable, Static
from textual.worker import Worker, WorkerState

from racer_tui.app.screens.base import RacerScreen, error_message
from racer_tui.app.widgets.coach_map import CoachMap
from racer_tui.app.widgets.footer import RacerFooter
from racer_tui.app.widgets.speed_trace import SpeedTraceChart
from racer_tui.app.widgets.table_fill import FittedTable
from sim.coach.lap_analysis import coach_sentence

if TYPE_CHECKING:  # the coach's numpy and osqp load when a lap is coached, not with the app
    from sim.garage.coach_session import Coaching


COLUMNS = ("sector", "lost", "time", "limit")
LEGEND = "lost in a sector: green < 10 %, yellow < 30 %, red more; the limit line dim"
SHORT_LEGEND = "lost: green <10 % · yellow <30 % · red more"


def summary_text(coaching: Coaching) -> Text:
    report = coaching.report
    text = Text()
    text.append(f"{report.seconds:.3f} s", style="bold")
    text.append(f", {report.gap_words} ")
    if coaching.limit is coaching.car_limit:
        text.append(f"({report.flying_limit:.3f} s with any action)")
    else:
        text.append(f"({report.flying_limit:.3f} s within its actions; ")
        text.append(f"{coaching.car_limit.flying_seconds:.3f} s with any)")
    if report.from_rest:  # the table's limits are the standing lap's: say so, or they disagree
        text.append(f"; sectors against the standing limit, {report.limit_seconds:.3f} s")
    return text


@dataclass
class CoachingReady(Message):
    coaching: Coaching


class CoachScreen(RacerScreen[None]):
    """A lap explained; `load` makes the coaching (it runs in a worker)."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "leave", "Back"),
        # The sector table takes these itself; here so the help lists them.
        Binding("down", "sector(1)", "Next sector", show=False),
        Binding("up", "sector(-1)", "Previous sector", show=False),
    ]
    DEFAULT_CSS = """
    CoachScreen { padding: 0 1; }
    CoachScreen #coach-title { text-style: bold; color: $accent; height: 1; }
    CoachScreen #coach-summary { height: auto; max-height: 2; }
    CoachScreen #coach-body { height: 1fr; min-height: 8; }
    CoachScreen #coach-left { width: 1fr; }
    CoachScreen #coach-legend { height: 1; color: $text-muted; }
    CoachScreen #coach-sectors { width: 34; height: 1fr; }
    CoachScreen #coach-sentence { height: 2; }
    CoachScreen SpeedTraceChart { height: 6; }
    """

    def __init__(self, who: str, which: str, load: Callable[[], Coaching]) -> None:
        """`who` drove the lap (a model, a racer); `which` says which lap until the coaching
        names it ("latest evaluation", "lap 3")."""
        super().__init__()
        self.who, self.which = who, which
        self._load = load
        self.coaching: Coaching | None = None
        self._order: list[int] = []  # table row -> index into the report's sectors

    def compose(self) -> ComposeResult:
        yield Static(Text(f"Coach · {self.who}, {self.which}"), id="coach-title")
        yield Static(Text("Working out the limit lap and reading the lap…"), id="coach-summary")
        with Horizontal(id="coach-body"):
            with Vertical(id="coach-left"):
                yield CoachMap(id="coach-map")
                yield Static("", id="coach-legend")
            yield FittedTable(id="coach-sectors", cursor_type="row", zebra_stripes=True)
        yield Static("", id="coach-sentence")
        yield SpeedTraceChart(id="coach-speed")
        yield RacerFooter()

    def on_mount(self) -> None:
        table = self.query_one("#coach-sectors", DataTable)
        for column in COLUMNS:
            table.add_column(column, key=column)
        table.focus()
        self._coach()

    def on_resize(self) -> None:
        self._show_legend()

    def action_leave(self) -> None:
        self.dismiss(None)

    def action_sector(self, step: int) -> None:
        table = self.query_one("#coach-sectors", DataTable)
        table.focus()
        table.move_cursor(row=max(table.cursor_row + step, 0))

    @work(thread=True, exclusive=True, group="coach", exit_on_error=False)
    def _coach(self) -> None:
        self.post_message(CoachingReady(self._load()))

    def on_coaching_ready(self, message: CoachingReady) -> None:
        coaching = self.coaching = message.coaching
        title = f"Coach · {self.who} on {coaching.track.name}, {coaching.report.label}"
        self.query_one("#coach-title", Static).update(Text(title))
        self.query_one("#coach-summary", Static).update(summary_text(coaching))
        sectors = coaching.report.sectors
        self._order = sorted(range(len(sectors)), key=lambda i: sectors[i].lost, reverse=True)
        table = self.query_one("#coach-sectors", DataTable)
        table.clear()
        for index in self._order:
            item = sectors[index]
            table.add_row(
                Text(item.sector.name),
                Text(item.lost_text, justify="right"),
                Text(f"{item.seconds:.2f}", justify="right"),
                Text(f"{item.limit_seconds:.2f}", justify="right"),
            )
        self.query_one(CoachMap).show(coaching)
        self.query_one(SpeedTraceChart).show(coaching.report.trace)
        self._show_legend()
        self._choose(0)

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        worker = event.worker
        if worker.group != "coach" or worker.state is not WorkerState.ERROR:
            return super().on_worker_state_changed(event)
        assert worker.error is not None
        # Said where the lap would be, and kept: the view has nothing else to show.
        problem = Text(error_message(worker.error), style="bold red")
        problem.append("\nEsc goes back.", style="default")
        self.query_one("#coach-summary", Static).update(problem)
        return None

    @on(DataTable.RowHighlighted, "#coach-sectors")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        self._choose(event.cursor_row)

    def _choose(self, row: int) -> None:
        if self.coaching is None or not 0 <= row < len(self._order):
            return

        index = self._order[row]
        self.query_one(CoachMap).choose(index)
        sentence = coach_sentence(self.coaching.report.sectors[index])
        self.query_one("#coach-sentence", Static).update(Text(sentence))

    def _show_legend(self) -> None:
        if self.coaching is None:
            return
        legend = self.query_one("#coach-legend", Static)
        width = legend.size.width or self.size.width
        legend.update(Text(LEGEND if len(LEGEND) <= width else SHORT_LEGEND))

"""Who races a head-to-head, and over how many laps: chosen from the Races screen's
drivers (space chooses, Enter races), the cars lined up in the order they were chosen."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from rich.segment import Segment
from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical
from textual.strip import Strip
from textual.widgets import Button, Checkbox, Label, Select, SelectionList, Static

from racer_tui.app.screens.dialogs import FormDialog, show_problem
from sim.race.head_to_head import MAX_CARS, MIN_CARS

# Laps to race (first past the line), or None: most laps in the window.
LAP_CHOICES: tuple[tuple[str, int | None], ...] = (
    ("3 laps (head-to-head rules)", 3),
    ("1 lap", 1),
    ("2 laps", 2),
    ("5 laps", 5),
    ("10 laps", 10),
    ("most laps in the window", None),
)
WHOLE_WINDOW = 0  # the laps select's value for None (a Select cannot hold None)
CHOSEN = "✓"


@dataclass(frozen=True)
class HeadToHeadRequest:
    drivers: tuple[int, ...]  # indices into the drivers offered, in grid order
    laps: int | None


class ChosenDrivers(SelectionList[int]):
    """The drivers to choose from: space chooses or lets go, Enter races. A chosen driver's
    box holds a tick, an unchosen one's nothing: Textual draws an X in both and tells them
    apart by colour alone."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("enter", "screen.confirm", "Race", show=False),
    ]

    def render_line(self, y: int) -> Strip:
        strip = super().render_line(y)
        segments = list(strip)
        if len(segments) < 2 or segments[1].text != Checkbox.BUTTON_INNER:
            return strip
        index = self.scroll_offset.y + y
        chosen = index < self.option_count and self.get_option_at_index(index).value in (
            self.selected
        )
        segments[1] = Segment(CHOSEN if chosen else " ", segments[1].style)
        return Strip(segments, strip.cell_length)


class HeadToHeadDialog(FormDialog[HeadToHeadRequest]):
    """Choose two to six drivers and the race's length."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "cancel", "Cancel")]
    COMPACT_FIELDS_BELOW_ROWS = 30
    # A garage of many models scrolls in the list: the length and the buttons stay in view.
    DEFAULT_CSS = """
    HeadToHeadDialog #h2h-drivers { height: auto; max-height: 8; }
    HeadToHeadDialog #h2h-drivers.-compact { border: none; padding: 0; max-height: 6; }
    """

    def __init__(self, drivers: Sequence[str], first: int | None, track_name: str) -> None:
        """`first`: the driver highlighted on the Races screen, chosen already."""
        super().__init__()
        self._drivers = list(drivers)
        self._first = first
        self._track_name = track_name

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Label(Text(f"Head-to-head on {self._track_name}"), classes="dialog-title")
            yield Static(
                f"Space chooses {MIN_CARS} to {MAX_CARS} drivers, lined up in the order "
                "chosen. Enter races.",
                classes="dialog-body",
            )
            yield ChosenDrivers(
                *[(Text(label), k, k == self._first) for k, label in enumerate(self._drivers)],
                id="h2h-drivers",
            )
            yield Static(id="h2h-grid")
            yield Label("Length", classes="field-label")
            yield Select(
                [(label, WHOLE_WINDOW if laps is None else laps) for label, laps in LAP_CHOICES],
                value=3,
                allow_blank=False,
                id="h2h-laps",
            )
            yield from self.form_buttons("Race (enter)")

    def on_mount(self) -> None:
        self.focus_first(self.query_one(ChosenDrivers))
        self._show_grid()

    def on_resize(self) -> None:
        super().on_resize()
        short = self.app.size.height < self.COMPACT_FIELDS_BELOW_ROWS
        self.query_one(ChosenDrivers).set_class(short, "-compact")

    @on(SelectionList.SelectedChanged)
    def _choice_changed(self) -> None:
        show_problem(self.query_one("#problem", Static), "")
        self._show_grid()

    def _show_grid(self) -> None:
        """The grid as chosen so far, in words: a choice's mark alone is colour only."""
        chosen = self.query_one(ChosenDrivers).selected
        grid = Text("Grid: ", style="bold")
        if not chosen:
            grid.append("nobody chosen yet", style="dim")
        for place, k in enumerate(chosen, start=1):
            grid.append(f"{'  ' if place > 1 else ''}{place} ")
            grid.append(self._drivers[k])
        self.query_one("#h2h-grid", Static).update(grid)

    @on(Button.Pressed, "#confirm")
    def action_confirm(self) -> None:
        chosen = tuple(self.query_one(ChosenDrivers).selected)
        if not MIN_CARS <= len(chosen) <= MAX_CARS:
            show_problem(
                self.query_one("#problem", Static),
                f"Choose {MIN_CARS} to {MAX_CARS} drivers with space ({len(chosen)} chosen).",
            )
            self.query_one(ChosenDrivers).focus()
            return
        laps = self.query_one("#h2h-laps", Select).value
        self.dismiss(HeadToHeadRequest(chosen, None if laps == WHOLE_WINDOW else int(str(laps))))

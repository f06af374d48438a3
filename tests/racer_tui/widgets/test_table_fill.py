"""Tables fit their width: names lose their end, the least important columns collapse, and
the table fits again when the terminal changes size."""

from __future__ import annotations

from typing import Any

from textual.app import App, ComposeResult

from racer_tui.app.widgets.table_fill import (
    Col,
    FittedTable,
    distinct_width,
    fill_table,
    fit_widths,
)
from tests.racer_tui.screens.tui_helpers import painted

COLUMNS = (
    Col("racer", keep=3, shrink_to=8, collapses=False),
    Col("best lap"),
    Col("model", keep=2, shrink_to=6),
    Col("submitted", keep=1),
)
NATURAL = [31, 8, 20, 10]  # what the cells need; each column also takes 1 cell each side


def test_a_table_that_fits_keeps_every_column_whole() -> None:
    assert fit_widths(NATURAL, COLUMNS, room=200, padding=1) == NATURAL


def test_the_least_important_column_collapses_first() -> None:
    # 77 cells needed with the date, 65 without it.
    assert fit_widths(NATURAL, COLUMNS, room=70, padding=1) == [31, 8, 20, None]


def test_a_column_that_can_shrink_loses_only_what_is_needed() -> None:
    assert fit_widths(NATURAL, COLUMNS, room=60, padding=1) == [31, 8, 15, None]


def test_a_shrunk_column_collapses_when_shrinking_is_not_enough() -> None:
    # Without the model the racer fits whole: it is not cut for a model that then goes.
    assert fit_widths(NATURAL, COLUMNS, room=45, padding=1) == [31, 8, None, None]


def test_a_name_shrinks_but_never_collapses_and_the_essential_stay() -> None:
    assert fit_widths(NATURAL, COLUMNS, room=25, padding=1) == [13, 8, None, None]
    # Narrower than the essentials at their narrowest: they stay, and the table scrolls.
    assert fit_widths(NATURAL, COLUMNS, room=10, padding=1) == [8, 8, None, None]


def test_a_name_shrunk_before_a_collapse_gets_the_room_back() -> None:
    columns = (
        Col("racer", keep=0, shrink_to=8, collapses=False),
        Col("best lap"),
        Col("laps", keep=1),
    )
    # The racer shrinks first (to 24), the laps column still has to go, and the racer
    # then gets back what it gave.
    assert fit_widths([31, 8, 30], columns, room=45, padding=1) == [31, 8, None]


ROWS = [
    [f"racer number {n} with a long name", f"{10 + n}.000", "bolt", "2024-05-01"] for n in range(30)
]


class OneTable(App[None]):
    def compose(self) -> ComposeResult:
        yield FittedTable(id="table", cursor_type="row")

    def on_mount(self) -> None:
        fill_table(self.query_one(FittedTable), COLUMNS, ROWS, keys=[str(n) for n in range(30)])


def header(app: App[Any]) -> str:
    return painted(app.query_one(FittedTable)).splitlines()[0]


async def test_the_table_fits_again_when_the_terminal_changes_size() -> None:
    app = OneTable()
    async with app.run_test(size=(40, 12)) as pilot:
        await pilot.pause()
        table = app.query_one(FittedTable)
        assert header(app).split() == ["racer", "best", "lap"]
        first = painted(table).splitlines()[1]
        assert "racer number 0 with a" in first and "…" in first and "long name" not in first
        table.move_cursor(row=17)
        await pilot.resize_terminal(100, 12)
        await pilot.pause()
        assert header(app).split() == ["racer", "best", "lap", "model", "submitted"]
        assert table.cursor_row == 17  # the racer's place in the list is kept, in view
        assert "racer number 17 with a long name" in painted(table)
        assert table.virtual_size.width <= table.scrollable_content_region.width


async def test_home_and_end_go_to_the_first_and_last_row() -> None:
    # The host walk: Home left the Garage's highlight where it was.
    app = OneTable()
    async with app.run_test(size=(60, 12)) as pilot:
        await pilot.pause()
        table = app.query_one(FittedTable)
        table.move_cursor(row=12)
        await pilot.press("end")
        assert table.cursor_row == len(ROWS) - 1
        await pilot.press("home")
        assert table.cursor_row == 0 and table.scroll_y == 0


def test_a_nights_result_of_ten_seconds_or_more_is_never_cut() -> None:
    # A new host's walk at 60x20: "best 10.5…" (the column gave way to 10 characters).
    from racer_tui.app.screens.nights import HEAT_COLUMNS

    columns = [column if isinstance(column, Col) else Col(column) for column in HEAT_COLUMNS]
    natural = [1, 12, 14, len("best 10.569")]
    widths = fit_widths(natural, columns, room=30, padding=1)
    assert widths[3] == len("best 10.569")


def test_names_that_must_stay_apart_are_cut_no_shorter_than_tells_them_apart() -> None:
    montgo = ["Alexandra Montgomery", "Alexandra Montgolfier", "bob"]
    # "Alexandra Montgo…" would be both: the first letter after it stays.
    assert distinct_width(montgo) == len("Alexandra Montgom…")
    # A Cyrillic а reads as a Latin a: "аna-…" and "ana-…" differ in their code points but
    # look the same, so the first letter after "ana-" stays.
    assert distinct_width(["\u0430na-fast", "ana-slow"]) == len("ana-f…")
    assert distinct_width(["ana", "bob"]) == len("a…")  # at 1, both would be "…"
    assert distinct_width([]) == 1


class Montgos(App[None]):
    def compose(self) -> ComposeResult:
        yield FittedTable(id="table", cursor_type="row")

    def on_mount(self) -> None:
        columns = [Col("racer", keep=1, shrink_to=4, collapses=False, stays_distinct=True)]
        rows = [["Alexandra Montgomery"], ["Alexandra Montgolfier"]]
        fill_table(self.query_one(FittedTable), [*columns, Col("wins")], [[*r, "3"] for r in rows])


async def test_a_table_too_narrow_for_two_names_still_tells_them_apart() -> None:
    app = Montgos()
    async with app.run_test(size=(24, 6)) as pilot:
        await pilot.pause()
        names = [line.split()[:2] for line in painted(app.query_one(FittedTable)).splitlines()[1:3]]
        assert names == [["Alexandra", "Montgom…"], ["Alexandra", "Montgol…"]]


def test_names_cut_in_the_middle_stay_apart_when_asked() -> None:
    """The host walk: "Bracket Night" and "Bracket Fight" both read "Brack…ight" at 60x20."""
    from racer_tui.app.widgets.table_fill import _shortened  # how a cell is cut

    names = ["Bracket Night", "Bracket Fight"]
    width = distinct_width(names, middle=True)
    assert width < len(names[0])
    cut = {str(_shortened(name, width, middle=True)) for name in names}
    assert len(cut) == 2
    assert len({str(_shortened(name, width - 1, middle=True)) for name in names}) == 1

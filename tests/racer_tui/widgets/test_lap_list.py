"""The timekeeper's laps: the newest shown as they come, the view following the selection,
and the laps that do not fit counted in the header."""

from __future__ import annotations

from rich.text import Text
from textual.app import App, ComposeResult

from racer_tui.app.widgets.lap_list import LapList
from tests.racer_tui.screens.tui_helpers import painted


class Laps(App[None]):
    CSS = "LapList { height: 5; }"  # a header and four laps

    def compose(self) -> ComposeResult:
        yield LapList()


def laps(count: int) -> list[tuple[tuple[str, ...], Text]]:
    times = [f"0:{n:02d}.000" for n in range(1, count + 1)]
    return [((str(n), time, time, "0"), Text("✓")) for n, time in enumerate(times, 1)]


def shown(widget: LapList) -> list[str]:
    return [line.split()[0] for line in painted(widget).splitlines()[1:] if line.strip()]


async def test_the_view_follows_the_selection_and_counts_what_does_not_fit() -> None:
    app = Laps()
    async with app.run_test(size=(60, 8)) as pilot:
        widget = app.query_one(LapList)
        widget.show(laps(10), select_last=True)
        await pilot.pause()
        assert shown(widget) == ["7", "8", "9", "10"]
        assert "↑6 ↓0" in painted(widget).splitlines()[0]
        await pilot.press("up", "up", "up")  # within the view: it stays put
        await pilot.pause()
        assert widget.selected == 6 and shown(widget) == ["7", "8", "9", "10"]
        await pilot.press("up")  # past its top: it moves by one lap
        await pilot.pause()
        assert shown(widget) == ["6", "7", "8", "9"]
        assert "↑5 ↓1" in painted(widget).splitlines()[0]
        await pilot.click(LapList, offset=(2, 3))  # the third lap shown
        assert widget.selected == 7
        widget.show(laps(11), select_last=True)  # a new lap: it is shown and chosen
        await pilot.pause()
        assert widget.selected == 10 and shown(widget)[-1] == "11"
